//! `slitpath plan`: the whole pipeline from an STL (or STEP) to G-code, with the JSON report.

use glam::{DVec2, DVec3};
use slitpath::gcode::Post;
use slitpath::mesh::{self, MeshOptions};
use slitpath::origin::OriginChoice;
use slitpath::plan::{Facets, Optimise, PlanOptions, Planner, RingSpread};
use slitpath::spiral::{Cut, Direction};
use slitpath::step::StepOptions;
use slitpath::toolpath::Axes;
use std::path::Path;
use std::time::Instant;

/// The command-line values, before validation.
pub struct Args<'a> {
    pub part: &'a Path,
    pub radius: f64,
    pub scallop: f64,
    pub axes: u8,
    pub lead: f64,
    pub tilt: f64,
    pub post: &'a str,
    pub origin: &'a str,
    pub direction: &'a str,
    pub cut: &'a str,
    pub feed: f64,
    pub plunge_feed: f64,
    pub spindle: f64,
    pub safe_z: Option<f64>,
    pub verify_samples: usize,
    pub facets: &'a str,
    pub optimise: &'a str,
    pub alpha: f64,
    pub spread: &'a str,
}

pub fn options(a: Args<'_>) -> Result<PlanOptions, String> {
    let post: Post = a.post.parse().map_err(|e| format!("--post: {e}"))?;
    let axes = match a.axes {
        3 => Axes::default(),
        5 => Axes::Five { lead_deg: a.lead, tilt_deg: a.tilt },
        n => return Err(format!("--axes {n}: use 3 or 5")),
    };
    let direction = match a.direction {
        "inward" => Direction::Inward,
        "outward" => Direction::Outward,
        d => return Err(format!("--direction `{d}`: use inward or outward")),
    };
    let cut = match a.cut {
        "climb" => Cut::Climb,
        "conventional" => Cut::Conventional,
        c => return Err(format!("--cut `{c}`: use climb or conventional")),
    };
    let facets = match a.facets {
        "exact" => Facets::Exact,
        "smooth" => Facets::Smooth,
        f => return Err(format!("--facets `{f}`: use exact or smooth")),
    };
    let optimise = match a.optimise {
        "tpsfo" => Optimise::Tpsfo,
        "none" => Optimise::None,
        o => return Err(format!("--optimise `{o}`: use tpsfo or none")),
    };
    let spread = match a.spread {
        "need" => RingSpread::Need,
        "none" => RingSpread::None,
        s => return Err(format!("--spread `{s}`: use need or none")),
    };
    let part_name = a.part.file_stem().map_or("part".into(), |s| s.to_string_lossy().into_owned());
    Ok(PlanOptions {
        radius_mm: a.radius,
        scallop_mm: a.scallop,
        origin: parse_origin(a.origin)?,
        direction,
        cut,
        axes,
        post,
        feed_mm_min: a.feed,
        plunge_feed_mm_min: a.plunge_feed,
        spindle_rpm: a.spindle,
        safe_z_mm: a.safe_z,
        verify_samples: a.verify_samples,
        part_name,
        facets,
        optimise,
        alpha: a.alpha,
        spread,
    })
}

/// `auto`, `centroid`, `hole:N`, `X,Y,Z` or `uv:U,V`.
pub fn parse_origin(s: &str) -> Result<OriginChoice, String> {
    let numbers = |t: &str| -> Result<Vec<f64>, String> {
        t.split(',').map(|p| p.trim().parse::<f64>().map_err(|_| format!("--origin: `{p}` is not a number"))).collect()
    };
    Ok(match s {
        "auto" => OriginChoice::Auto,
        "centroid" => OriginChoice::Centroid,
        _ if s.starts_with("hole:") => {
            OriginChoice::Hole(s[5..].parse().map_err(|_| format!("--origin {s}: `{}` is not a hole number", &s[5..]))?)
        }
        _ if s.starts_with("uv:") => match numbers(&s[3..])?.as_slice() {
            [u, v] => OriginChoice::Plane(DVec2::new(*u, *v)),
            _ => return Err(format!("--origin {s}: expected uv:U,V")),
        },
        _ => match numbers(s)?.as_slice() {
            [x, y, z] => OriginChoice::Point3d(DVec3::new(*x, *y, *z)),
            _ => return Err(format!("--origin `{s}`: use auto, centroid, hole:N, X,Y,Z or uv:U,V")),
        },
    })
}

/// The CPU time of the calling thread, ms (Linux: `/proc/thread-self/schedstat`), for
/// `SLITPATH_CPU_CLOCK`: with `RAYON_NUM_THREADS=1` the plan runs on one thread, and its stages'
/// CPU times do not swell on a machine busy with other work as their wall times do.
fn thread_cpu_ms() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    Some(stat.split_whitespace().next()?.parse::<f64>().ok()? * 1e-6)
}

/// Reads, plans and returns the G-code and the report JSON.
pub fn run(
    part: &Path,
    mesh_options: &MeshOptions,
    step_options: &StepOptions,
    options: &PlanOptions,
) -> Result<(String, String), String> {
    let started = Instant::now();
    let cpu_clock = std::env::var_os("SLITPATH_CPU_CLOCK").is_some();
    let now = || if cpu_clock { thread_cpu_ms().unwrap_or(f64::NAN) } else { started.elapsed().as_secs_f64() * 1e3 };
    let name = part.display();
    let (mesh, step) = crate::part::load(part, mesh_options, step_options, &now)?;
    let t_read = now();
    let planner = Planner::new(mesh, &now).map_err(|e| format!("{name}: {e}"))?;
    let mut plan = planner.plan(options, &mut |_, _, _| {}, &now).map_err(|e| format!("{name}: {e}"))?;
    plan.report.timings_ms.read = t_read;
    plan.report.timings_ms.total += t_read;
    if let Some(note) = handle_note(&plan.report.mesh) {
        eprintln!("note: {name}: {note}");
    }
    for retry in &plan.report.spacing_retries {
        eprintln!("note: {name}: {}", retry.describe());
    }
    for warning in &plan.report.warnings {
        eprintln!("warning: {name}: {warning}");
    }
    let json = crate::part::report_json(&plan.report, step.as_ref())?;
    Ok((plan.gcode, json))
}

/// One line on the handles cut to plan a part of genus > 0 (`None` for genus 0).
pub fn handle_note(report: &mesh::MeshReport) -> Option<String> {
    let cuts = &report.handle_cuts;
    if cuts.is_empty() {
        return None;
    }
    let lengths: Vec<String> = cuts.iter().map(|c| format!("{:.2}", c.length_mm)).collect();
    Some(format!(
        "genus {}: cut along {} handle loop{} ({} mm cut; the path runs along both sides of each cut, see mesh.handle_cuts in the report)",
        report.genus,
        cuts.len(),
        if cuts.len() == 1 { "" } else { "s" },
        lengths.join(", ")
    ))
}
