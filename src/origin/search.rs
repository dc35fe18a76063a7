//! The search for the pole with the least E_min (seed 000 eqs. 19–22, Pseudocode C-2): the
//! annulus option of every hole, then gradient descent from several starts with a
//! finite-difference gradient (eq. 20), backtracking steps (eq. 21's shrinking step, made
//! adaptive), and the jump out of a hole to the best point of its offset curve (eq. 22).

use super::energy::{Energy, EnergyEvaluator};
use super::locate::boundary_distance;
use crate::slitmap::{PlanarDomain, SlitMap};
use glam::DVec2;

/// Initial step length, as a fraction of the domain size.
const FIRST_STEP: f64 = 0.05;
/// Longest step, as a fraction of the domain size.
const MAX_STEP: f64 = 0.25;
/// Finite-difference step of the gradient (eq. 20), as a fraction of the domain size.
const FD_STEP: f64 = 1e-3;
/// Disk poles closer than this fraction of the domain size to a boundary are not tried: the map
/// crowds there and the energy is dominated by discretisation error.
const MARGIN: f64 = 1e-3;
/// Points sampled on a hole's offset curve (eq. 22).
const OFFSET_SAMPLES: usize = 16;
/// Offset of that curve from the hole, as a fraction of the domain size.
const OFFSET: f64 = 0.02;
/// A descent that comes this near (a fraction of the domain size) to an earlier descent's end
/// at least as good as itself has joined that end's basin, and stops. At 1 % the later starts
/// of the 40k-face panel crept down the same bowl for 39 of the search's 66 evaluations and
/// ended beside the first start's end. At 2 % the panel's search takes 51, and the fixtures' and
/// shared meshes' 8 % fewer in all, for the same pole on all but two (plate_3_holes, E_min
/// 0.04 % higher; beetle, 0.13 % lower). At 5 % beetle's pole was 2.7 % worse.
const JOIN: f64 = 0.02;
/// At most this many face centres are candidates for the spread-out starts.
const START_CANDIDATES: usize = 1024;

/// Where a pole lies, for the search.
enum Region {
    /// Inside the domain, at least the margin from every boundary.
    Disk,
    /// Inside hole `j` (loop index ≥ 1).
    Hole(usize),
    /// Outside, on or too near a boundary.
    Infeasible,
}

pub(crate) struct Search<'s, 'a> {
    ev: &'s EnergyEvaluator<'a>,
    domain: &'s PlanarDomain,
    budget: usize,
    /// Domain size (bounding-box diagonal of the flattened plane).
    scale: f64,
    tolerance_rel: f64,
    pub evaluations: usize,
    pub trace: Vec<(DVec2, f64)>,
    /// The pole with the least E_min so far, its energy and its slit map.
    pub best: Option<(DVec2, Energy, SlitMap)>,
    /// Best point of each hole's offset curve, once computed (`None` inside: no feasible point).
    offsets: Vec<Option<Option<(DVec2, f64)>>>,
    /// Energies (with their maps) computed ahead, in parallel, of the sequential search asking
    /// for them (see [`Search::prefetch`]).
    ahead: Vec<(DVec2, Option<(Energy, SlitMap)>)>,
}

impl<'s, 'a> Search<'s, 'a> {
    pub fn new(ev: &'s EnergyEvaluator<'a>, domain: &'s PlanarDomain, budget: usize, tolerance_rel: f64) -> Self {
        Self {
            ev,
            domain,
            budget,
            scale: super::locate::domain_size(domain),
            tolerance_rel,
            evaluations: 0,
            trace: Vec::new(),
            best: None,
            offsets: vec![None; domain.loops.len()],
            ahead: Vec::new(),
        }
    }

    fn exhausted(&self) -> bool {
        self.evaluations >= self.budget
    }

    fn region(&self, p: DVec2) -> Region {
        match self.ev.solver().classify_pole(p) {
            Ok(None) if boundary_distance(self.domain, p) >= MARGIN * self.scale => Region::Disk,
            Ok(Some(j)) => Region::Hole(j),
            _ => Region::Infeasible,
        }
    }

    /// E_min at `p`, recorded in the trace; None when the budget is spent or the pole is
    /// infeasible (a slit-map or energy error: skipped, never a failure of the search).
    pub fn eval(&mut self, p: DVec2) -> Option<f64> {
        if self.exhausted() {
            return None;
        }
        self.evaluations += 1;
        let (energy, map) = match self.ahead.iter().position(|(q, _)| *q == p) {
            Some(k) => self.ahead.swap_remove(k).1,
            None => self.ev.evaluate_with_map(p).ok(),
        }?;
        let e = energy.e_min;
        self.keep(p, energy, map);
        Some(e)
    }

    /// Evaluates the poles `points` that the search is about to ask for (or may), in parallel
    /// when there are threads (the wasm build has none: nothing is done there). The search's
    /// course is the sequential one whatever is fetched: [`Search::eval`] only takes the value
    /// from here instead of computing it. Unused values cost a thread's idle time, no more.
    /// With `disk_only`, only the points that are feasible disk poles (the search asks for the
    /// others through [`Search::eval_disk`], which skips them).
    fn prefetch(&mut self, points: &[DVec2], disk_only: bool) {
        if crate::par::threads() < 2 {
            return;
        }
        let room = self.budget.saturating_sub(self.evaluations);
        let todo: Vec<DVec2> = points
            .iter()
            .copied()
            .filter(|&p| !disk_only || matches!(self.region(p), Region::Disk))
            .filter(|&p| !self.ahead.iter().any(|(q, _)| *q == p))
            .take(room)
            .collect();
        if todo.len() < 2 {
            return; // one point gains nothing from a thread
        }
        let ev = self.ev;
        let energies = crate::par::each(todo.len(), |i| ev.evaluate_with_map(todo[i]).ok());
        self.ahead.extend(todo.into_iter().zip(energies));
    }

    /// Records an energy and its map evaluated outside the search (the centroid's).
    pub fn record(&mut self, p: DVec2, energy: Energy, map: SlitMap) {
        self.evaluations += 1;
        self.keep(p, energy, map);
    }

    /// Traces an evaluation, and keeps it when it is the best so far.
    fn keep(&mut self, p: DVec2, energy: Energy, map: SlitMap) {
        self.trace.push((p, energy.e_min));
        if self.best.as_ref().map_or(true, |(_, b, _)| energy.better_than(b)) {
            self.best = Some((p, energy, map));
        }
    }

    /// E_min at `p` if `p` is a feasible disk pole.
    fn eval_disk(&mut self, p: DVec2) -> Option<f64> {
        match self.region(p) {
            Region::Disk => self.eval(p),
            _ => None,
        }
    }

    /// The whole search after the centroid: every hole's annulus, then descents from `starts`
    /// points (the centroid first).
    pub fn run(&mut self, centroid: DVec2, centroid_e: f64, starts: usize) {
        let holes: Vec<DVec2> = (1..self.domain.loops.len()).map(|j| self.ev.solver().canonical_hole_pole(j)).collect();
        let starts = self.starts(centroid, starts);
        self.prefetch(&[&holes[..], &starts[1..]].concat(), false);
        for &p in &holes {
            self.eval(p);
        }
        let mut ends: Vec<(DVec2, f64)> = Vec::new();
        for (k, s) in starts.into_iter().enumerate() {
            let e = if k == 0 { Some(centroid_e) } else { self.eval(s) };
            let Some(e) = e else { continue };
            if let Some(end) = self.descend(s, e, &ends) {
                ends.push(end);
            }
            if self.exhausted() {
                break;
            }
        }
    }

    /// Deterministic starts: `centroid`, then points spread over the domain by farthest-point
    /// sampling of face centres, each as far as possible from the boundary and the earlier
    /// starts (like centres of largest inscribed circles).
    fn starts(&self, centroid: DVec2, count: usize) -> Vec<DVec2> {
        let mut out = vec![centroid];
        if count <= 1 {
            return out;
        }
        let tris = &self.domain.triangles;
        let stride = tris.len().div_ceil(START_CANDIDATES).max(1);
        // Each candidate's distance walks every boundary edge: in parallel.
        let cands: Vec<(DVec2, f64)> = crate::par::each(tris.len().div_ceil(stride), |k| {
            let c = tris[k * stride].iter().map(|&v| self.domain.positions[v as usize]).sum::<DVec2>() / 3.0;
            (c, boundary_distance(self.domain, c))
        })
        .into_iter()
        .filter(|&(_, d)| d >= 2.0 * MARGIN * self.scale)
        .collect();
        while out.len() < count {
            let mut best: Option<(DVec2, f64)> = None;
            for &(c, d) in &cands {
                let score = out.iter().fold(d, |m, s| m.min(s.distance(c)));
                if best.map_or(true, |(_, b)| score > b) {
                    best = Some((c, score));
                }
            }
            match best {
                Some((c, score)) if score > 0.0 => out.push(c),
                _ => break,
            }
        }
        out
    }

    /// Gradient descent from `p` (energy `e`) until the step falls below the tolerance or the
    /// budget is spent; stops early next to an earlier endpoint that is at least as good.
    /// Returns the endpoint.
    fn descend(&mut self, mut p: DVec2, mut e: f64, ends: &[(DVec2, f64)]) -> Option<(DVec2, f64)> {
        let h = FD_STEP * self.scale;
        let min_step = self.tolerance_rel * self.scale;
        let mut step = FIRST_STEP * self.scale;
        'outer: while !self.exhausted() {
            if ends.iter().any(|&(q, eq)| q.distance(p) < JOIN * self.scale && eq <= e) {
                break;
            }
            let Some(g) = self.gradient(p, e, h) else { break };
            let len = g.length();
            if !(len > 0.0 && len.is_finite()) {
                break;
            }
            let dir = -g / len;
            loop {
                if step < min_step || self.exhausted() {
                    break 'outer;
                }
                // This step and the halved one, should it fail.
                self.prefetch(&[step, 0.5 * step].map(|s| p + dir * s), true);
                let q = p + dir * step;
                let next = match self.region(q) {
                    Region::Disk => self.eval(q).map(|eq| (q, eq)),
                    // Eq. 22: out of the hole to the best point on its offset curve.
                    Region::Hole(j) => self.offset_best(j),
                    Region::Infeasible => None,
                };
                match next {
                    Some((q, eq)) if eq < e => {
                        (p, e) = (q, eq);
                        step = (2.0 * step).min(MAX_STEP * self.scale);
                        break;
                    }
                    _ => step *= 0.5,
                }
            }
        }
        Some((p, e))
    }

    /// Forward-difference gradient (eq. 20) along x and y, backward where the forward point is
    /// infeasible; a component is 0 when both are.
    fn gradient(&mut self, p: DVec2, e: f64, h: f64) -> Option<DVec2> {
        let mut g = DVec2::ZERO;
        self.prefetch(&[p + DVec2::X * h, p + DVec2::Y * h], true);
        for (k, u) in [DVec2::X, DVec2::Y].into_iter().enumerate() {
            let d = if let Some(ef) = self.eval_disk(p + u * h) {
                (ef - e) / h
            } else if let Some(eb) = self.eval_disk(p - u * h) {
                (e - eb) / h
            } else if self.exhausted() {
                return None;
            } else {
                0.0
            };
            g[k] = d;
        }
        Some(g)
    }

    /// The best feasible point of hole `j`'s offset curve (eq. 22): `OFFSET_SAMPLES` points
    /// equally spaced by arc length on the hole loop, moved along the edge normal into the
    /// domain (halving the offset up to 4 times where the point is not a feasible disk pole).
    fn offset_best(&mut self, j: usize) -> Option<(DVec2, f64)> {
        if let Some(cached) = self.offsets[j] {
            return cached;
        }
        let lp = &self.domain.loops[j];
        let pos = |k: usize| self.domain.positions[lp[k % lp.len()] as usize];
        let total: f64 = (0..lp.len()).map(|k| pos(k).distance(pos(k + 1))).sum();
        let mut points = Vec::with_capacity(OFFSET_SAMPLES);
        let (mut k, mut run) = (0usize, 0.0);
        for s in 0..OFFSET_SAMPLES {
            let target = total * (s as f64 + 0.5) / OFFSET_SAMPLES as f64;
            while k < lp.len() && run + pos(k).distance(pos(k + 1)) < target {
                run += pos(k).distance(pos(k + 1));
                k += 1;
            }
            let (a, b) = (pos(k), pos(k + 1));
            let len = a.distance(b);
            if len <= 0.0 {
                continue;
            }
            let on = a + (b - a) * ((target - run) / len).clamp(0.0, 1.0);
            // The domain is on the left of every loop.
            let normal = (b - a).perp() / len;
            points.push((on, normal));
        }
        let first: Vec<DVec2> = points.iter().map(|&(on, normal)| on + normal * (OFFSET * self.scale)).collect();
        self.prefetch(&first, true);
        let mut best: Option<(DVec2, f64)> = None;
        for (on, normal) in points {
            let mut off = OFFSET * self.scale;
            for _ in 0..5 {
                let q = on + normal * off;
                // Half the offset from every boundary: not squeezed against another loop.
                if matches!(self.region(q), Region::Disk) && boundary_distance(self.domain, q) > 0.5 * off {
                    if let Some(e) = self.eval(q) {
                        if best.map_or(true, |(_, b)| e < b) {
                            best = Some((q, e));
                        }
                    }
                    break;
                }
                off *= 0.5;
            }
        }
        if !self.exhausted() {
            self.offsets[j] = Some(best);
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flatten::{self, FlattenInput, FlattenOptions};
    use crate::mesh::{self, MeshOptions};
    use crate::origin::{pole_to_3d, OriginOptions};
    use crate::slitmap::{SlitMapOptions, SlitMapSolver};
    use glam::DVec3;

    #[test]
    fn descents_from_every_spread_start_reach_the_centre_of_a_symmetric_part() {
        // find_origin starts at the centroid, which is the centre here: this checks that the
        // descents from the other, off-centre starts get there too.
        let surface =
            mesh::from_triangles(&crate::fixtures::symmetric_4_holes(), &MeshOptions::default()).unwrap().surface;
        let flat = flatten::flatten(FlattenInput::from(&surface), &FlattenOptions::default()).unwrap();
        let domain = PlanarDomain::of_surface(&surface, flat.uv);
        let solver = SlitMapSolver::new(&domain, &SlitMapOptions::default()).unwrap();
        let options = OriginOptions::default();
        let ev = EnergyEvaluator::new(&surface, &solver, &options).unwrap();
        let mut s = Search::new(&ev, &domain, 10_000, options.tolerance_rel);
        let centroid = crate::origin::centroid_pole(&domain);
        let starts = s.starts(centroid, 5);
        assert_eq!(starts.len(), 5);
        for &start in &starts[1..] {
            let e = s.eval(start).unwrap();
            let (end, e_end) = s.descend(start, e, &[]).unwrap();
            let p3 = pole_to_3d(&surface, &domain, end, None);
            let off = p3.distance(DVec3::new(0.0, 0.0, 8.0));
            assert!(e_end < e && off < 0.02 * 113.0, "start {start}: ended {off} mm from the centre");
            // The starts are spread: none is near the centre.
            assert!(pole_to_3d(&surface, &domain, start, None).truncate().length() > 10.0);
        }
    }
}
