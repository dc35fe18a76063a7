//! The plan report (`slitpath plan --report`, the page's figures) and the G-code header: what a
//! plan tells its user besides the path. Plain data built from the stages' outputs.

use super::{Facets, PlanOptions, Planner, RejectedPole, RingSpread, SpacingRetry, SpreadSummary, Timings};
use crate::flatten::FlattenReport;
use crate::mesh::creases::FacetValleys;
use crate::mesh::{MeshReport, Surface};
use crate::optimise::OptimiseReport;
use crate::origin::{Origin, OriginChoice};
use crate::slitmap::{Mode, SlitMap};
use crate::spacing::Rings;
use crate::spiral::{Cut, Direction};
use crate::toolpath::{Axes, Clearance};
use crate::verify::{self, Verification};
use glam::DVec3;
use serde::Serialize;

/// The path figures of the report.
#[derive(Debug, Clone, Serialize)]
pub struct PathSummary {
    pub length_mm: f64,
    /// The length over the flat-plate bound area / (2·√(2Rh)) (DESIGN.md, "Path length at equal
    /// finish"): about 1.05 for evenly spaced passes on a gently curved part.
    pub length_over_ideal: f64,
    pub points: usize,
    pub retractions: usize,
    pub max_turn_deg: f64,
    pub rho2: f64,
    pub time_min: f64,
    /// Ball centres moved off facets nearer than R ([`toolpath::clear_facets`]; zeros with
    /// [`Facets::Smooth`]).
    pub clearance: Clearance,
}

/// The optimisation as the plan report shows it: the stage's own report, and which field the
/// written path follows.
#[derive(Debug, Clone, Serialize)]
pub struct OptimiseSummary {
    /// `tpsfo` when the path follows the optimised field, `conformal` when the planner kept the
    /// slit map's own (see `fallback`).
    pub path_field: &'static str,
    /// What the optimisation did (absent when it failed).
    #[serde(flatten)]
    pub stage: Option<OptimiseReport>,
    /// Why the conformal map's path was written instead of the optimised field's: the optimised
    /// one failed, or it left more than h where the conformal map's does not.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fallback: Option<String>,
    /// The optimised path's length when it was not kept, mm.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub optimised_length_mm: Option<f64>,
}

impl Default for OptimiseSummary {
    fn default() -> Self {
        Self { path_field: "tpsfo", stage: None, fallback: None, optimised_length_mm: None }
    }
}

/// The options as the report shows them (plain values, the CLI's names).
#[derive(Debug, Clone, Serialize)]
pub struct OptionsReport {
    pub radius_mm: f64,
    pub scallop_mm: f64,
    pub origin: String,
    pub direction: Direction,
    pub cut: Cut,
    pub axes: u8,
    pub lead_deg: Option<f64>,
    pub tilt_deg: Option<f64>,
    pub post: &'static str,
    pub feed_mm_min: f64,
    pub plunge_feed_mm_min: f64,
    pub spindle_rpm: f64,
    pub safe_z_mm: Option<f64>,
    pub verify_samples: usize,
    pub facets: Facets,
    pub spread: RingSpread,
}

impl OptionsReport {
    pub(super) fn new(o: &PlanOptions) -> Self {
        let (axes, lead_deg, tilt_deg) = match o.axes {
            Axes::Three { .. } => (3, None, None),
            Axes::Five { lead_deg, tilt_deg } => (5, Some(lead_deg), Some(tilt_deg)),
        };
        Self {
            radius_mm: o.radius_mm,
            scallop_mm: o.scallop_mm,
            origin: origin_name(&o.origin),
            direction: o.direction,
            cut: o.cut,
            axes,
            lead_deg,
            tilt_deg,
            post: o.post.name(),
            feed_mm_min: o.feed_mm_min,
            plunge_feed_mm_min: o.plunge_feed_mm_min,
            spindle_rpm: o.spindle_rpm,
            safe_z_mm: o.safe_z_mm,
            verify_samples: o.verify_samples,
            facets: o.facets,
            spread: o.spread,
        }
    }
}

/// `auto`, `centroid`, `hole:N`, `X,Y,Z` (3D point) or `uv:U,V` (flattened-plane pole).
pub fn origin_name(o: &OriginChoice) -> String {
    match o {
        OriginChoice::Auto => "auto".into(),
        OriginChoice::Centroid => "centroid".into(),
        OriginChoice::Hole(n) => format!("hole:{n}"),
        OriginChoice::Point3d(p) => format!("{},{},{}", p.x, p.y, p.z),
        OriginChoice::Plane(p) => format!("uv:{},{}", p.x, p.y),
    }
}

#[derive(Debug, Clone, Serialize)]
pub struct OriginReport {
    pub mode: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub annulus_hole: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub inner_radius: Option<f64>,
    pub pole_uv: [f64; 2],
    pub pole_3d: [f64; 3],
    pub e_min: f64,
    pub e_min_centroid: f64,
    pub uniformity: f64,
    pub evaluations: usize,
    /// Poles `auto` or `centroid` chose first and could not plan from (see [`MAX_FALLBACKS`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub rejected: Vec<RejectedPole>,
}

/// Where a peak of the verified finish lies: the verifier's sample ([`verify::ScallopAt`]), its
/// slit-domain image w = ρ·e^{iθ} and the rings either side of it.
#[derive(Debug, Clone, Serialize)]
pub struct PeakAt {
    #[serde(flatten)]
    pub sample: verify::ScallopAt,
    /// |w| and arg w of the sample's image.
    pub rho: f64,
    pub theta: f64,
    /// The ring outside the sample (larger radius) and the one inside it, indices into
    /// `ring_radii` (`None` beyond the first or the last ring).
    pub ring_outside: Option<usize>,
    pub ring_inside: Option<usize>,
}

impl PeakAt {
    /// The peak `at` located on `surface` (the map's vertices) in `map` between `radii`
    /// (outermost first); `None` when its face is not the surface's.
    pub fn locate(at: &verify::ScallopAt, surface: &Surface, map: &SlitMap, radii: &[f64]) -> Option<Self> {
        let [a, b, c] = *surface.triangles.get(at.face as usize)?;
        let corner = |v: u32| surface.positions.get(v as usize).copied();
        let (pa, pb, pc) = (corner(a)?, corner(b)?, corner(c)?);
        let w = |v: u32| map.w.get(v as usize).copied();
        let (wa, wb, wc) = (w(a)?, w(b)?, w(c)?);
        // The sample lies on the face: its barycentric coordinates are its closest point's.
        let [ba, bb, bc] = crate::mesh::nearest::closest_on_triangle(DVec3::from_array(at.position), pa, pb, pc);
        let image = wa * ba + wb * bb + wc * bc;
        let rho = image.length();
        let inside = radii.iter().position(|&r| r <= rho);
        let outside = match inside {
            Some(0) => None,
            Some(k) => Some(k - 1),
            None => radii.len().checked_sub(1),
        };
        Some(Self { sample: *at, rho, theta: image.y.atan2(image.x), ring_outside: outside, ring_inside: inside })
    }
}

/// The plan report (`slitpath plan --report`, and what the page shows).
#[derive(Debug, Clone, Serialize)]
pub struct PlanReport {
    pub options: OptionsReport,
    pub mesh: MeshReport,
    /// The flattening's method, disk blend, hole fillings and quality figures.
    pub flatten: FlattenReport,
    pub origin: OriginReport,
    /// Number of rings.
    pub rings: usize,
    /// Ring radii |w|, outermost first.
    pub ring_radii: Vec<f64>,
    /// Rings the spacing could not prove everywhere (see [`Rings::fold_compromises`],
    /// [`Rings::crease_compromises`] and [`Rings::gate_compromises`]): where the verifier's
    /// figures may exceed h, and why.
    pub fold_compromises: usize,
    pub crease_compromises: usize,
    pub gate_compromises: usize,
    /// Seed 003's optimisation of the field (absent with `--optimise none`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub optimise: Option<OptimiseSummary>,
    /// With `--spread need`: the spread field's path against the other (see [`SpreadSummary`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spread: Option<SpreadSummary>,
    /// Paths whose verification left more than h outside the facet valleys, spaced again for a
    /// smaller cusp ([`super::paths`]); empty when the first path kept h.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub spacing_retries: Vec<SpacingRetry>,
    pub path: PathSummary,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub verify: Option<Verification>,
    /// Where the verifier's largest scallop lies in the slit domain and between which rings
    /// (absent without verification, and for a spread field's path, whose rings are not circles
    /// of the map).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_scallop_at: Option<PeakAt>,
    /// The same for its largest scallop outside the facet valleys.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_outside_valleys_at: Option<PeakAt>,
    pub gouge_risk_area_mm2: f64,
    pub flipped_triangles: usize,
    /// With [`Facets::Exact`]: the concave creases where the STL's facets alone leave more than
    /// h for this R, whatever the path ([`crate::mesh::creases`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub facet_valleys: Option<FacetValleys>,
    /// What the user should know before trusting the G-code, in words (the CLI prints them on
    /// stderr, the page beside the figures).
    pub warnings: Vec<String>,
    pub timings_ms: Timings,
}

impl PlanReport {
    #[allow(clippy::too_many_arguments)]
    pub(super) fn new(
        planner: &Planner,
        options: &PlanOptions,
        origin: &Origin,
        map: &SlitMap,
        rings: &Rings,
        path: PathSummary,
        verification: Option<Verification>,
        timings_ms: Timings,
    ) -> Self {
        let (mode, annulus_hole, inner_radius) = match map.mode {
            Mode::Disk => ("disk", None, None),
            Mode::Annulus { hole, inner_radius } => ("annulus", Some(hole), Some(inner_radius)),
        };
        let mut report = Self {
            options: OptionsReport::new(options),
            mesh: planner.report.clone(),
            flatten: planner.flattening.report(),
            origin: OriginReport {
                mode,
                annulus_hole,
                inner_radius,
                pole_uv: origin.pole.to_array(),
                pole_3d: origin.pole_3d.to_array(),
                e_min: origin.energy.e_min,
                e_min_centroid: origin.centroid_energy.e_min,
                uniformity: origin.energy.uniformity,
                evaluations: origin.evaluations,
                rejected: Vec::new(),
            },
            rings: rings.rings.len(),
            ring_radii: rings.radii(),
            fold_compromises: rings.fold_compromises,
            crease_compromises: rings.crease_compromises,
            gate_compromises: rings.gate_compromises,
            optimise: None,
            spread: None,
            spacing_retries: Vec::new(),
            path,
            max_scallop_at: None,
            max_outside_valleys_at: None,
            verify: verification,
            gouge_risk_area_mm2: origin.energy.gouge_risk_area_mm2,
            flipped_triangles: map.flipped_triangles(),
            facet_valleys: None,
            warnings: Vec::new(),
            timings_ms,
        };
        if options.facets == Facets::Exact {
            let (r, h) = (options.radius_mm, options.scallop_mm);
            let valleys = crate::mesh::creases::facet_valleys(&planner.surface, r, h);
            if valleys.edges > 0 || valleys.pits > 0 {
                report.warnings.push(format!(
                    "the STL's facets alone leave up to {:.4} mm ({:.2} h) at {} concave creases ({:.1} mm of edges) and {} pits for a ball of radius {r} mm, whatever the path: if the STL tessellates a smooth surface, plan with --facets smooth; otherwise use a finer STL or a smaller ball (a smaller h would not help)",
                    valleys.max_depth_mm,
                    valleys.max_depth_mm / h,
                    valleys.edges,
                    valleys.length_mm,
                    valleys.pits
                ));
            }
            report.facet_valleys = Some(valleys);
        }
        if let Some(v) = &report.verify {
            let unresolved = report.path.clearance.unresolved;
            report.warnings.extend(gouge_warning(v.gouges, v.samples, v.max_gouge_mm, unresolved, options.radius_mm));
            let at = v.max_outside_valleys_at.map(|a| a.position);
            let (max, unreached) = (v.max_scallop_outside_valleys_mm, v.uncovered_fraction);
            report.warnings.extend(scallop_warning(max, at, unreached, options.scallop_mm, report.flipped_triangles));
        }
        let radii = rings.radii();
        let locate = |at: Option<&verify::ScallopAt>| at.and_then(|a| PeakAt::locate(a, &planner.surface, map, &radii));
        report.max_scallop_at = locate(report.verify.as_ref().and_then(|v| v.max_scallop_at.as_ref()));
        report.max_outside_valleys_at = locate(report.verify.as_ref().and_then(|v| v.max_outside_valleys_at.as_ref()));
        report
    }
}

/// The warning for a path the verifier finds gouging the part (`gouges` of its `samples` deeper
/// than its tolerance, the deepest `max_gouge_mm`), with the ball positions the facet clearance
/// could not lift (`unresolved`, see [`crate::toolpath::clear_facets`]): at a sixtieth of their
/// diagonal face, camelhead and mech-holes-shark gouged as deep as R where the ball wedged in
/// features narrower than itself, and only the report said so.
fn gouge_warning(
    gouges: usize,
    samples: usize,
    max_gouge_mm: f64,
    unresolved: usize,
    radius_mm: f64,
) -> Option<String> {
    if gouges == 0 {
        return None;
    }
    let wedged = if unresolved > 0 {
        format!(
            "; the ball could not be lifted clear of the facets at {unresolved} positions (a fin, groove or pit narrower than the ball)"
        )
    } else {
        String::new()
    };
    Some(format!(
        "the path gouges the part: the verifier found the ball up to {max_gouge_mm:.4} mm inside it at {gouges} of its {samples} samples{wedged}; use a ball smaller than {radius_mm} mm"
    ))
}

/// The warning for a path the verifier finds leaving `max_mm` > `h_mm` outside the facet valleys
/// (those have their own warning): where (`at`), the fraction of the surface the ball never
/// reaches, and the likely cause. At a pole the user chose where the slit map folds (gen14 of
/// the generated parts at (−15, 20, 0)), the path missed 3.4 % of the part, 140 h deep, and
/// only a note on the spacing's retry said so.
fn scallop_warning(
    max_mm: f64,
    at: Option<[f64; 3]>,
    unreached_fraction: f64,
    h_mm: f64,
    flipped_triangles: usize,
) -> Option<String> {
    if max_mm <= h_mm {
        return None;
    }
    let at = at.map_or(String::new(), |[x, y, z]| format!(" at ({x:.2}, {y:.2}, {z:.2})"));
    let unreached = if unreached_fraction > 0.0 {
        format!("; the ball never reaches {:.2} % of the surface", 100.0 * unreached_fraction)
    } else {
        String::new()
    };
    let cause = if flipped_triangles > 0 {
        let s = if flipped_triangles == 1 { "" } else { "s" };
        format!("; the slit map folds {flipped_triangles} triangle{s} at this origin: plan from another one")
    } else {
        String::new()
    };
    Some(format!(
        "the path leaves up to {max_mm:.4} mm ({:.2} h) outside the facet valleys{at}, over the limit h = {h_mm} mm{unreached}{cause}",
        max_mm / h_mm
    ))
}

/// Header lines of the G-code: options and path figures, no timings (deterministic output).
pub(super) fn header_lines(
    o: &PlanOptions,
    origin: &Origin,
    rings: &Rings,
    path: &PathSummary,
    optimised: bool,
    spread: bool,
) -> Vec<(String, String)> {
    let opts = OptionsReport::new(o);
    let mut field = if optimised {
        format!("seed 003 optimised, tpsfo, alpha {}", o.alpha)
    } else {
        "conformal slit map, seed 000".to_string()
    };
    if spread {
        field.push_str(", spread by each meridian's need");
    }
    let mut lines = vec![
        ("planner".to_string(), "slitpath conformal slit-map spiral".to_string()),
        ("field".into(), field),
        ("ball radius mm".into(), format!("{}", opts.radius_mm)),
        ("scallop mm".into(), format!("{}", opts.scallop_mm)),
        ("origin".into(), opts.origin),
        ("axes".into(), format!("{}", opts.axes)),
    ];
    if let (Some(l), Some(t)) = (opts.lead_deg, opts.tilt_deg) {
        lines.push(("lead tilt deg".into(), format!("{l} {t}")));
    }
    lines.extend([
        ("direction".into(), format!("{:?} {:?}", opts.direction, opts.cut).to_lowercase()),
        ("pole uv".into(), format!("{:.6} {:.6}", origin.pole.x, origin.pole.y)),
        ("rings".into(), format!("{}", rings.rings.len())),
        ("path length mm".into(), format!("{:.3}", path.length_mm)),
        ("points".into(), format!("{}", path.points)),
        ("estimated time min".into(), format!("{:.2}", path.time_min)),
    ]);
    lines
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_path_over_h_is_warned_about_with_where_and_what_it_misses() {
        assert_eq!(scallop_warning(0.0157, Some([0.0; 3]), 0.0, 0.0157, 0), None);
        let w = scallop_warning(0.016, None, 0.0, 0.0157, 0).unwrap();
        assert!(w.contains("(1.02 h)") && !w.contains("never reaches") && !w.contains("folds"), "{w}");
        // gen14 of the generated parts from the pole (−15, 20, 0).
        let w = scallop_warning(2.1928, Some([-28.6748, -10.8177, -1.6105]), 0.0336, 0.0157, 1).unwrap();
        assert!(w.contains("2.1928 mm (139.67 h)") && w.contains("at (-28.67, -10.82, -1.61)"), "{w}");
        assert!(w.contains("never reaches 3.36 %") && w.contains("folds 1 triangle at"), "{w}");
    }

    #[test]
    fn a_gouging_path_is_warned_about_with_its_depth_and_the_wedged_balls() {
        assert_eq!(gouge_warning(0, 100_000, 0.0, 12, 3.0), None);
        // face.stl at R 0.0035 mm (stop 45): 39 332 gouging samples, 478 603 wedged balls.
        let w = gouge_warning(39_332, 100_000, 0.0034709, 478_603, 0.0034711).unwrap();
        assert!(w.contains("0.0035 mm inside it at 39332 of its 100000 samples"), "{w}");
        assert!(w.contains("at 478603 positions") && w.ends_with("smaller than 0.0034711 mm"), "{w}");
        let w = gouge_warning(5, 20_000, 0.01, 0, 3.0).unwrap();
        assert!(!w.contains("positions") && w.contains("at 5 of its 20000 samples"), "{w}");
    }
}
