//! `slitpath coons`: seed 004's spiral over a closed band of four-sided STEP faces (issue 36
//! items 3–5), with the JSON report. When the faces are not such a band the error says why and
//! names the slit-map spiral (`slitpath plan`) that plans them on their tessellation;
//! `--fallback` plans that instead, `--compare` plans it too and adds its figures to the report.

use slitpath::coons::{self, CoonsOptions};
use slitpath::gcode::Post;
use slitpath::mesh::MeshOptions;
use slitpath::step::StepOptions;
use slitpath::toolpath::Axes;
use std::path::PathBuf;
use std::time::Instant;

/// The command-line options of `slitpath coons`.
#[derive(clap::Args)]
pub struct CoonsArgs {
    pub part: PathBuf,
    /// Ball radius, mm.
    #[arg(long, default_value_t = 3.0, allow_hyphen_values = true)]
    pub radius: f64,
    /// Scallop-height limit, mm.
    #[arg(long, default_value_t = 0.02, allow_hyphen_values = true)]
    pub scallop: f64,
    /// 5 (lead/tilt: a band faces every way round its loop) or 3 (fixed +Z).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u8).range(3..=5))]
    pub axes: u8,
    /// 5-axis lead angle, degrees.
    #[arg(long, default_value_t = 15.0, allow_hyphen_values = true)]
    pub lead: f64,
    /// 5-axis tilt angle, degrees.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub tilt: f64,
    /// ac (5-axis A/C with TCP), cl (APT CL data), linuxcnc or grbl (3-axis).
    #[arg(long, default_value = "ac")]
    pub post: String,
    /// Keep the raw Coons map (no composite-C1 smoothing of the seams round the loop).
    #[arg(long)]
    pub no_smooth: bool,
    /// Cutting and lead-in feeds, mm/min; spindle speed, rpm.
    #[arg(long, default_value_t = 1000.0, allow_hyphen_values = true)]
    pub feed: f64,
    #[arg(long, default_value_t = 300.0, allow_hyphen_values = true)]
    pub plunge_feed: f64,
    #[arg(long, default_value_t = 12000.0, allow_hyphen_values = true)]
    pub spindle: f64,
    /// Safe height, mm (default: above the highest tool point).
    #[arg(long, allow_hyphen_values = true)]
    pub safe_z: Option<f64>,
    /// Verifier samples (0 skips the verification).
    #[arg(long, default_value_t = 100_000)]
    pub verify_samples: usize,
    /// When the faces are not a band of four-sided faces, plan the slit-map spiral on their
    /// tessellation instead (as `slitpath plan` would) rather than stop with the reason.
    #[arg(long)]
    pub fallback: bool,
    /// Also plan the slit-map spiral on the band's tessellation and add its length and scallop
    /// to the report (`slitmap_comparison`).
    #[arg(long)]
    pub compare: bool,
    /// Where to write the G-code or CL data.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Where to write the report (JSON).
    #[arg(long)]
    pub report: Option<PathBuf>,
}

fn options(a: &CoonsArgs) -> Result<CoonsOptions, String> {
    let post: Post = a.post.parse().map_err(|e| format!("--post: {e}"))?;
    let axes = match a.axes {
        3 => Axes::default(),
        5 => Axes::Five { lead_deg: a.lead, tilt_deg: a.tilt },
        n => return Err(format!("--axes {n}: use 3 or 5")),
    };
    Ok(CoonsOptions {
        radius_mm: a.radius,
        scallop_mm: a.scallop,
        smooth: !a.no_smooth,
        axes,
        post,
        feed_mm_min: a.feed,
        plunge_feed_mm_min: a.plunge_feed,
        spindle_rpm: a.spindle,
        safe_z_mm: a.safe_z,
        verify_samples: a.verify_samples,
        part_name: a.part.file_stem().map_or("part".into(), |s| s.to_string_lossy().into_owned()),
        ..CoonsOptions::default()
    })
}

/// The slit-map planner with the same tool, scallop, axes and post.
fn slitmap(
    a: &CoonsArgs,
    mesh_options: &MeshOptions,
    step_options: &StepOptions,
    o: &CoonsOptions,
) -> Result<(String, String), String> {
    let options = slitpath::plan::PlanOptions {
        radius_mm: o.radius_mm,
        scallop_mm: o.scallop_mm,
        axes: o.axes,
        post: o.post,
        feed_mm_min: o.feed_mm_min,
        plunge_feed_mm_min: o.plunge_feed_mm_min,
        spindle_rpm: o.spindle_rpm,
        safe_z_mm: o.safe_z_mm,
        verify_samples: o.verify_samples,
        part_name: o.part_name.clone(),
        ..Default::default()
    };
    crate::plan::run(&a.part, mesh_options, step_options, &options)
}

/// Reads, plans and returns the program and the report JSON.
pub fn run(a: &CoonsArgs, mesh_options: &MeshOptions, step_options: &StepOptions) -> Result<(String, String), String> {
    let o = options(a)?;
    let name = a.part.display();
    let bytes = std::fs::read(&a.part).map_err(|e| format!("cannot read {name}: {e}"))?;
    if !slitpath::step::is_step(&bytes) {
        return Err(format!("{name}: the coons strategy needs a STEP file (its exact faces)"));
    }
    let started = Instant::now();
    let now = || started.elapsed().as_secs_f64() * 1e3;
    let model = slitpath::step::read(&bytes).map_err(|e| format!("{name}: {e}"))?;
    let faces = step_options.faces.clone().unwrap_or_else(|| model.faces.iter().map(|f| f.id).collect());
    let plan = match coons::plan(&model, &faces, &o, &now) {
        Ok(p) => p,
        Err(e) if e.is_not_a_band() => {
            if a.fallback {
                eprintln!(
                    "slitpath: {name}: {e}; planning the slit-map spiral on the tessellation instead (--fallback)"
                );
                return slitmap(a, mesh_options, step_options, &o);
            }
            let list: Vec<String> = faces.iter().map(|f| f.to_string()).collect();
            return Err(format!(
                "{name}: {e}. Seed 004 needs a closed band of four-sided faces; the slit-map spiral plans these faces on their tessellation: `slitpath plan {name} --faces {} --axes 5 …` (or add --fallback)",
                list.join(",")
            ));
        }
        Err(e) => return Err(format!("{name}: {e}")),
    };
    let mut value = serde_json::to_value(&plan.report).map_err(|e| e.to_string())?;
    if a.compare {
        let step_options = StepOptions { faces: Some(faces), ..step_options.clone() };
        let (_, json) = slitmap(a, mesh_options, &step_options, &o)?;
        let other: serde_json::Value = serde_json::from_str(&json).map_err(|e| e.to_string())?;
        let pick = |path: &[&str]| path.iter().try_fold(&other, |v, k| v.get(k)).cloned().unwrap_or_default();
        let comparison = serde_json::json!({
            "length_mm": pick(&["path", "length_mm"]),
            "max_scallop_mm": pick(&["verify", "max_scallop_mm"]),
            "p95_scallop_mm": pick(&["verify", "p95_scallop_mm"]),
            "retractions": pick(&["path", "retractions"]),
            "coons_length_over_slitmap": plan.report.length_mm / pick(&["path", "length_mm"]).as_f64().unwrap_or(f64::NAN),
        });
        if let serde_json::Value::Object(map) = &mut value {
            map.insert("slitmap_comparison".into(), comparison);
        }
    }
    let json = serde_json::to_string_pretty(&value).map_err(|e| e.to_string())?;
    Ok((plan.gcode, json))
}
