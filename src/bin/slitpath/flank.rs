//! `slitpath flank`: 5-axis flank milling with a conical tool (seed 002) from an STL to A/C
//! G-code or CL data, with the JSON report (the optimiser's figures and the flank verifier's).

use glam::DVec3;
use slitpath::flank::{self, ConeTool, FlankOptions, Weights};
use slitpath::gcode::Post;
use slitpath::mesh::MeshOptions;
use slitpath::step::StepOptions;
use std::path::PathBuf;
use std::time::Instant;

/// The command-line options of `slitpath flank`.
#[derive(clap::Args)]
pub struct FlankArgs {
    pub part: PathBuf,
    /// Radius of the flute at the tool's tip, mm.
    #[arg(long, allow_hyphen_values = true)]
    pub tip_radius: f64,
    /// Radius of the flute at its top (towards the shank), mm.
    #[arg(long, allow_hyphen_values = true)]
    pub top_radius: f64,
    /// Length of the flute along the axis, mm.
    #[arg(long, allow_hyphen_values = true)]
    pub flute_length: f64,
    /// Machining direction X,Y,Z: the strips run along it; the tool's shank points along
    /// n × direction (n the surface normal towards the tool): reverse it to turn the tool round.
    #[arg(long, allow_hyphen_values = true)]
    pub direction: String,
    /// Number of strips (default: as many as fit across the surface).
    #[arg(long)]
    pub strips: Option<usize>,
    /// accuracy (w2 = 1, w3 = 1e-3), g1 (w2 = 1e-4, w3 = 1) or W2,W3.
    #[arg(long, default_value = "accuracy")]
    pub weights: String,
    /// ac (5-axis table-table A/C with TCP) or cl (APT CL data).
    #[arg(long, default_value = "ac")]
    pub post: String,
    /// Spacing of the poses along the guiding curves, mm (default: 1/100 of the part's diagonal).
    #[arg(long)]
    pub step: Option<f64>,
    /// Samples per tool axis (seed 002 eq. 11).
    #[arg(long, default_value_t = 30)]
    pub samples: usize,
    /// Chordal tolerance of the moves, mm.
    #[arg(long, default_value_t = 0.002)]
    pub chord: f64,
    /// Largest tool-axis step between moves, degrees.
    #[arg(long, default_value_t = 0.5)]
    pub angle: f64,
    /// Radius of the shank (or neck) above the flutes, mm (default: the top radius).
    #[arg(long, allow_hyphen_values = true)]
    pub shank_radius: Option<f64>,
    /// Gauge length: from the tool tip to the holder's face, mm (default: 3 × the flute length).
    #[arg(long, allow_hyphen_values = true)]
    pub gauge_length: Option<f64>,
    /// Radius of the holder, mm (default: twice the shank radius).
    #[arg(long, allow_hyphen_values = true)]
    pub holder_radius: Option<f64>,
    /// Length of the holder along the axis from its face, mm.
    #[arg(long, default_value_t = 40.0, allow_hyphen_values = true)]
    pub holder_length: f64,
    /// Clearance wanted from the holder and, on rapids, the flutes, mm.
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
    pub margin: f64,
    /// Approach and retract distance along the surface normal, mm.
    #[arg(long, default_value_t = 10.0)]
    pub retract: f64,
    /// Every strip in the same direction (default: every other one backwards).
    #[arg(long)]
    pub one_way: bool,
    /// Cutting and approach feeds, mm/min; spindle speed, rpm.
    #[arg(long, default_value_t = 1000.0, allow_hyphen_values = true)]
    pub feed: f64,
    #[arg(long, default_value_t = 300.0, allow_hyphen_values = true)]
    pub plunge_feed: f64,
    #[arg(long, default_value_t = 12000.0, allow_hyphen_values = true)]
    pub spindle: f64,
    /// Decimals of coordinates and angles.
    #[arg(long, default_value_t = 4)]
    pub decimals: usize,
    /// Flank verifier samples (0 skips the verification).
    #[arg(long, default_value_t = 20_000)]
    pub verify_samples: usize,
    /// Where to write the G-code or CL data.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Where to write the report (JSON).
    #[arg(long)]
    pub report: Option<PathBuf>,
}

/// `X,Y,Z` → a vector.
fn vec3(flag: &str, s: &str) -> Result<DVec3, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|p| p.trim().parse::<f64>().map_err(|_| format!("--{flag}: `{p}` is not a number")))
        .collect::<Result<_, _>>()?;
    match v.as_slice() {
        [x, y, z] => Ok(DVec3::new(*x, *y, *z)),
        _ => Err(format!("--{flag}: expected X,Y,Z, got `{s}`")),
    }
}

/// The options of the command line (validated by the planner itself).
pub fn options(a: &FlankArgs) -> Result<FlankOptions, String> {
    let weights = match a.weights.as_str() {
        "accuracy" => Weights::accuracy(),
        "g1" => Weights::g1(),
        w => match w.split(',').map(|p| p.trim().parse::<f64>()).collect::<Result<Vec<f64>, _>>().as_deref() {
            Ok([w2, w3]) => Weights { approx: *w2, g1: *w3, ..Weights::accuracy() },
            _ => return Err(format!("--weights `{w}`: use accuracy, g1 or W2,W3")),
        },
    };
    let post = match a.post.as_str() {
        "ac" => Post::Ac,
        "cl" => Post::Cl,
        p => return Err(format!("--post `{p}`: flank milling is 5-axis, use ac or cl")),
    };
    Ok(FlankOptions {
        tool: ConeTool { tip_radius_mm: a.tip_radius, top_radius_mm: a.top_radius, flute_length_mm: a.flute_length },
        direction: vec3("direction", &a.direction)?,
        strips: a.strips,
        pose_step_mm: a.step,
        samples_per_axis: a.samples,
        weights,
        chord_tolerance_mm: a.chord,
        angle_tolerance_deg: a.angle,
        shank_radius_mm: a.shank_radius,
        gauge_length_mm: a.gauge_length,
        holder_radius_mm: a.holder_radius,
        holder_length_mm: a.holder_length,
        collision_margin_mm: a.margin,
        retract_mm: a.retract,
        zigzag: !a.one_way,
        feed_mm_min: a.feed,
        plunge_feed_mm_min: a.plunge_feed,
        spindle_rpm: a.spindle,
        post,
        decimals: a.decimals,
        part_name: a.part.file_stem().map_or("part".into(), |s| s.to_string_lossy().into_owned()),
        verify_samples: a.verify_samples,
        ..FlankOptions::default()
    })
}

/// Reads, plans and returns the program and the report JSON.
pub fn run(a: &FlankArgs, mesh_options: &MeshOptions, step_options: &StepOptions) -> Result<(String, String), String> {
    let options = options(a)?;
    let started = Instant::now();
    let now = || started.elapsed().as_secs_f64() * 1e3;
    let name = a.part.display();
    let (mesh, step) = crate::part::load(&a.part, mesh_options, step_options, &now)?;
    let plan = flank::plan(&mesh.surface, &options, &mut |_, _, _| {}, &now).map_err(|e| format!("{name}: {e}"))?;
    let json = crate::part::report_json(&plan.report, step.as_ref())?;
    Ok((plan.gcode, json))
}
