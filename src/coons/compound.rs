//! The compound Coons domain of a band (seed 004 §2, Fig. 3(c) and 14): face (i, j) covers
//! [i, i + 1] × [j, j + 1] of the (U, V) plane, U periodic with period `around` (the band's
//! loop), V in [0, `across`]. Shared sides have the same arc-length parameter on both faces, so
//! the compound map is continuous (eq. 3); [`super::smooth`] makes it C¹ across the seams round
//! the loop.

use super::band::{Band, BandFace};
use super::patch::{Eval, Patch};
use super::side::ParamSide;
use super::CoonsError;
use crate::step::model::Model;

/// The band's faces as Coons patches, `patches[i + around * j]`.
#[derive(Clone, Debug)]
pub struct Compound {
    pub around: usize,
    pub across: usize,
    pub patches: Vec<Patch>,
}

/// The Coons map of the band face `f`.
pub fn patch(model: &Model, f: &BandFace) -> Result<Patch, CoonsError> {
    let face = &model.faces[f.index];
    let s = &face.surface;
    let first = f.bottom[0].curve.point(f.bottom[0].from);
    let p00 = s.invert(first, None);
    let bottom = ParamSide::new(s, &f.bottom, p00);
    let right = ParamSide::new(s, &f.right, bottom.end());
    let left = ParamSide::new(s, &f.left, bottom.start());
    let top = ParamSide::new(s, &f.top, left.end());
    // The loop must close in the parameters: a face that wraps round a periodic surface has no
    // planar domain for its Coons map.
    let tol = 1e-6 * (1.0 + top.end().length());
    let gap = (top.end() - right.end()).length();
    if !(gap <= tol) {
        return Err(CoonsError::Domain {
            face: f.id,
            reason: format!(
                "its sides do not close in the surface's parameters (gap {gap:.3e}): does it wrap round the surface?"
            ),
        });
    }
    let corners = [bottom.start(), bottom.end(), top.start(), top.end()];
    Ok(Patch {
        id: f.id,
        surface: s.clone(),
        sign: if face.same_sense { 1.0 } else { -1.0 },
        bottom,
        top,
        left,
        right,
        corners,
        correction: None,
    })
}

impl Compound {
    pub fn new(model: &Model, band: &Band) -> Result<Compound, CoonsError> {
        let patches = band.faces.iter().map(|f| patch(model, f)).collect::<Result<Vec<_>, _>>()?;
        Ok(Compound { around: band.around, across: band.across, patches })
    }

    pub fn patch(&self, i: usize, j: usize) -> &Patch {
        &self.patches[i % self.around + self.around * j]
    }

    /// The face holding (U, V) and the local (s, t): U wrapped into [0, around), V clamped to
    /// [0, across]; on a seam the face to the right (above), except at V = across.
    pub fn locate(&self, u: f64, v: f64) -> (usize, usize, f64, f64) {
        let m = self.around as f64;
        let u = u.rem_euclid(m);
        let v = v.clamp(0.0, self.across as f64);
        let i = (u.floor() as usize).min(self.around - 1);
        let j = (v.floor() as usize).min(self.across - 1);
        (i, j, u - i as f64, v - j as f64)
    }

    /// The compound map at (U, V).
    pub fn at(&self, u: f64, v: f64) -> Eval {
        let (i, j, s, t) = self.locate(u, v);
        self.patch(i, j).eval(s, t)
    }

    /// The largest distance between the 3D points two faces give a shared side, over `k` + 1
    /// points of every side shared round the loop and across rows, mm (eq. 3; 0 in exact
    /// arithmetic).
    pub fn seam_gap_mm(&self, k: usize) -> f64 {
        let mut gap: f64 = 0.0;
        for j in 0..self.across {
            for i in 0..self.around {
                let a = self.patch(i, j);
                let b = self.patch(i + 1, j);
                for q in 0..=k {
                    let t = q as f64 / k as f64;
                    gap = gap.max((a.eval(1.0, t).x - b.eval(0.0, t).x).length());
                    if j + 1 < self.across {
                        let c = self.patch(i, j + 1);
                        gap = gap.max((a.eval(t, 1.0).x - c.eval(t, 0.0).x).length());
                    }
                }
            }
        }
        gap
    }

    /// The smallest det ∂(u,v)/∂(s,t) over a `k` × `k` grid of every face (cell centres), relative
    /// to its value at the face's centre (so > 0 means regular and of one orientation).
    pub fn det_j_min_rel(&self, k: usize) -> f64 {
        let mut worst = f64::INFINITY;
        for p in &self.patches {
            let centre = p.det_j(0.5, 0.5);
            for a in 0..k {
                for b in 0..k {
                    let (s, t) = ((a as f64 + 0.5) / k as f64, (b as f64 + 0.5) / k as f64);
                    worst = worst.min(p.det_j(s, t) / centre);
                }
            }
        }
        worst
    }
}
