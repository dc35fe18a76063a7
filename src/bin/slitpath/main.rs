//! `slitpath` — the native command-line planner.
//!
//! Subcommands:
//! - `info PART.stl [--json]`: the mesh report (topology, boundary loops, machined top surface).
//! - `map PART.stl [--pole-3d X,Y,Z | --pole hole:N | --pole centroid] --json OUT.json [--svg OUT.svg]`:
//!   flattens the part and writes its conformal slit map.
//! - `plan PART.stl --radius R --scallop H [--axes 3|5] [--post …] [--origin …] -o OUT [--report R.json]`:
//!   plans the spiral and writes G-code (or CL data) and the plan report.
//! - `flank PART.stl --tip-radius … --top-radius … --flute-length … --direction X,Y,Z [--strips N]
//!   [--weights accuracy|g1|W2,W3] --post ac|cl -o OUT [--report R.json]`: 5-axis flank milling
//!   with a conical tool (seed 002); `--axis` gives the tool's side of an open surface.
//! - `coons PART.step --faces 12,13,… [--radius R --scallop H --axes 5 --post ac --no-smooth
//!   --fallback --compare] -o OUT [--report R.json]`: seed 004's spiral over a closed band of
//!   four-sided STEP faces (Coons maps on the exact faces).
//! - `faces PART.step [--json]`: the STEP faces, their surface types, areas and neighbours.
//!
//! Every command that reads a part takes STL or STEP (by content or a `.step`/`.stp` name);
//! for STEP, `--faces 12,13` chooses the faces and `--chordal-tol-mm` the tessellation.
//! - `fixture NAME -o FILE.stl`: writes one of the analytic test surfaces as binary STL.
//!
//! Errors go to stderr as one line and the exit code is non-zero; no panic reaches the user.

// The planner allocates and frees large buffers stage after stage; glibc's malloc hands them
// back to the kernel and takes fresh, zeroed pages each time (a tenth of a 40k-face plan).
#[cfg(not(target_arch = "wasm32"))]
#[global_allocator]
static ALLOC: mimalloc::MiMalloc = mimalloc::MiMalloc;

#[cfg(not(target_arch = "wasm32"))]
mod coons;
#[cfg(not(target_arch = "wasm32"))]
mod flank;
#[cfg(not(target_arch = "wasm32"))]
mod map;
#[cfg(not(target_arch = "wasm32"))]
mod part;
#[cfg(not(target_arch = "wasm32"))]
mod plan;
#[cfg(not(target_arch = "wasm32"))]
mod svg;

#[cfg(not(target_arch = "wasm32"))]
mod cli {
    use clap::{Parser, Subcommand};
    use slitpath::{fixtures, mesh};
    use std::path::PathBuf;

    #[derive(Parser)]
    #[command(name = "slitpath", version, about = "Spiral finishing toolpaths for freeform surfaces with holes")]
    struct Cli {
        #[command(subcommand)]
        command: Command,
    }

    #[derive(Subcommand)]
    enum Command {
        /// Reads an STL and prints its mesh report.
        Info {
            part: PathBuf,
            /// Print exactly one JSON object on stdout.
            #[arg(long)]
            json: bool,
            #[command(flatten)]
            mesh: MeshArgs,
        },
        /// Flattens the part and writes its conformal slit map (seed 000 §2.1).
        Map {
            part: PathBuf,
            /// `centroid` (default) or `hole:N` (the annulus map of hole N, 1-based).
            #[arg(long, value_parser = crate::map::parse_pole, conflicts_with = "pole_3d")]
            pole: Option<crate::map::PoleChoice>,
            /// A pole in the part's coordinates, moved to the nearest surface point.
            #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
            pole_3d: Option<[f64; 3]>,
            /// Where to write the JSON (`mode`, `inner_radius`, `slits`, `flipped_triangles`,
            /// `flatten`, `vertices`, `uv`, `w`).
            #[arg(long)]
            json: PathBuf,
            /// Where to write an SVG drawing of the flattened and the slit domain.
            #[arg(long)]
            svg: Option<PathBuf>,
            #[command(flatten)]
            mesh: MeshArgs,
        },
        /// Plans the spiral finishing path and writes its G-code (or CL data).
        Plan {
            part: PathBuf,
            /// Ball radius, mm.
            #[arg(long, default_value_t = 3.0, allow_hyphen_values = true)]
            radius: f64,
            /// Scallop-height limit, mm.
            #[arg(long, default_value_t = 0.02, allow_hyphen_values = true)]
            scallop: f64,
            /// 3 (fixed axis +Z) or 5 (lead/tilt, seed 000 eq. 5).
            #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u8).range(3..=5))]
            axes: u8,
            /// 5-axis lead angle, degrees.
            #[arg(long, default_value_t = 15.0, allow_hyphen_values = true)]
            lead: f64,
            /// 5-axis tilt angle, degrees.
            #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
            tilt: f64,
            /// linuxcnc, grbl, ac (5-axis A/C with TCP) or cl (APT CL data).
            #[arg(long, default_value = "linuxcnc")]
            post: String,
            /// auto, centroid, hole:N, X,Y,Z (a point of the part) or uv:U,V (flattened plane).
            #[arg(long, default_value = "auto", allow_hyphen_values = true)]
            origin: String,
            /// inward or outward.
            #[arg(long, default_value = "inward")]
            direction: String,
            /// climb or conventional (for an M3 spindle).
            #[arg(long, default_value = "climb")]
            cut: String,
            /// Cutting feed, mm/min.
            #[arg(long, default_value_t = 1000.0, allow_hyphen_values = true)]
            feed: f64,
            /// Lead-in feed, mm/min.
            #[arg(long, default_value_t = 300.0, allow_hyphen_values = true)]
            plunge_feed: f64,
            /// Spindle speed, rpm.
            #[arg(long, default_value_t = 12000.0, allow_hyphen_values = true)]
            spindle: f64,
            /// Safe height, mm (default: above the highest tool point).
            #[arg(long, allow_hyphen_values = true)]
            safe_z: Option<f64>,
            /// Verifier samples (0 skips the verification).
            #[arg(long, default_value_t = 100_000)]
            verify_samples: usize,
            /// exact (the STL is the part: the ball never enters a facet) or smooth (the STL
            /// tessellates a smooth surface: the ball follows the vertex normals).
            #[arg(long, default_value = "exact")]
            facets: String,
            /// tpsfo (seed 003: the rings follow the surface, shorter paths) or none (the
            /// conformal slit map's circles, seed 000).
            #[arg(long, default_value = "tpsfo")]
            optimise: String,
            /// Seed 003's α, mm²: larger gives smoother, longer paths.
            #[arg(long, default_value_t = 10.0, allow_hyphen_values = true)]
            alpha: f64,
            /// none (every meridian gets the rings its worst one needs) or need (a path whose
            /// rings each meridian gets by its own need is planned first, and written when it
            /// keeps h: 8 % shorter on average, about 1.6 times the planning time).
            #[arg(long, default_value = "none")]
            spread: String,
            /// Where to write the G-code or CL data.
            #[arg(short, long)]
            output: PathBuf,
            /// Where to write the plan report (JSON).
            #[arg(long)]
            report: Option<PathBuf>,
            #[command(flatten)]
            mesh: MeshArgs,
        },
        /// Plans 5-axis flank milling with a conical tool (seed 002) and writes A/C G-code or CL
        /// data. `--axis` is the side of the surface the tool is on.
        Flank {
            #[command(flatten)]
            args: crate::flank::FlankArgs,
            #[command(flatten)]
            mesh: MeshArgs,
        },
        /// Plans seed 004's spiral over a closed band of four-sided STEP faces (`--faces`):
        /// Coons maps on the exact faces, one continuous spiral, composite-C1 seams.
        Coons {
            #[command(flatten)]
            args: crate::coons::CoonsArgs,
            #[command(flatten)]
            mesh: MeshArgs,
        },
        /// Lists the faces of a STEP file: id, surface type, area, loops, adjacent faces.
        Faces {
            part: PathBuf,
            /// Print exactly one JSON object on stdout.
            #[arg(long)]
            json: bool,
            #[command(flatten)]
            mesh: MeshArgs,
        },
        /// Writes an analytic test surface as binary STL (or STEP: step:NAME, see --list).
        Fixture {
            /// One of the fixture names (see `slitpath fixture --list`).
            #[arg(required_unless_present = "list")]
            name: Option<String>,
            #[arg(short, long, required_unless_present = "list")]
            output: Option<PathBuf>,
            /// List the names.
            #[arg(long)]
            list: bool,
        },
    }

    #[derive(clap::Args)]
    struct MeshArgs {
        /// Tool axis (towards the tool), e.g. `0,0,1`.
        #[arg(long, value_parser = parse_vec3, default_value = "0,0,1", allow_hyphen_values = true)]
        axis: [f64; 3],
        /// Closed solids: faces within this angle of the tool axis form the machined top, degrees.
        #[arg(long, default_value_t = mesh::MeshOptions::default().wall_angle_deg)]
        wall_angle: f64,
        /// Maximum number of triangles accepted.
        #[arg(long, default_value_t = mesh::MeshOptions::default().max_triangles)]
        max_triangles: usize,
        /// STEP input: the faces to machine, by id (`12,13,…`; default: all, when they form one
        /// open surface). `slitpath faces PART.step` lists them.
        #[arg(long)]
        faces: Option<String>,
        /// STEP input: largest distance between the facets and the exact surfaces, mm.
        #[arg(long, default_value_t = slitpath::step::StepOptions::default().chordal_tol_mm)]
        chordal_tol_mm: f64,
    }

    impl MeshArgs {
        fn options(&self) -> mesh::MeshOptions {
            mesh::MeshOptions {
                tool_axis: glam::DVec3::from_array(self.axis),
                wall_angle_deg: self.wall_angle,
                max_triangles: self.max_triangles,
                ..Default::default()
            }
        }

        pub fn step_options(&self) -> Result<slitpath::step::StepOptions, String> {
            Ok(slitpath::step::StepOptions {
                chordal_tol_mm: self.chordal_tol_mm,
                faces: self.faces.as_deref().map(crate::part::parse_faces).transpose()?,
                ..Default::default()
            })
        }
    }

    fn parse_vec3(s: &str) -> Result<[f64; 3], String> {
        let parts: Vec<f64> = s
            .split(',')
            .map(|p| p.trim().parse::<f64>().map_err(|_| format!("`{p}` is not a number")))
            .collect::<Result<_, _>>()?;
        <[f64; 3]>::try_from(parts).map_err(|_| format!("expected three comma-separated numbers, got `{s}`"))
    }

    pub fn run() -> Result<(), String> {
        let cli = Cli::parse();
        match cli.command {
            Command::Info { part, json, mesh: args } => {
                let (out, step) = crate::part::load(&part, &args.options(), &args.step_options()?, &|| 0.0)?;
                if json {
                    let text = crate::part::report_json(&out.report, step.as_ref())?;
                    println!("{}", serde_json::from_str::<serde_json::Value>(&text).map_err(|e| e.to_string())?);
                } else {
                    print_report(&part.display().to_string(), &out.report);
                    if let Some(s) = step {
                        let ids: Vec<String> = s.faces.iter().map(|f| format!("#{} {}", f.id, f.surface)).collect();
                        println!("STEP faces: {}", ids.join(", "));
                        println!(
                            "chordal error {:.5} mm (tolerance {} mm), unit {}",
                            s.chordal_error_mm, s.chordal_tol_mm, s.unit
                        );
                    }
                }
                Ok(())
            }
            Command::Faces { part, json, mesh: args } => crate::part::print_faces(&part, &args.step_options()?, json),
            Command::Map { part, pole, pole_3d, json, svg, mesh: args } => {
                let (out, _) = crate::part::load(&part, &args.options(), &args.step_options()?, &|| 0.0)?;
                let pole = match (pole, pole_3d) {
                    (_, Some(p)) => crate::map::PoleChoice::Point3d(glam::DVec3::from_array(p)),
                    (Some(p), None) => p,
                    (None, None) => crate::map::PoleChoice::Centroid,
                };
                let result = crate::map::run(&out.surface, &pole).map_err(|e| format!("{}: {e}", part.display()))?;
                let text = serde_json::to_string(&result.json).map_err(|e| e.to_string())?;
                write(&json, text.as_bytes())?;
                if let Some(svg) = svg {
                    write(&svg, result.svg.as_bytes())?;
                }
                Ok(())
            }
            Command::Plan {
                part,
                radius,
                scallop,
                axes,
                lead,
                tilt,
                post,
                origin,
                direction,
                cut,
                feed,
                plunge_feed,
                spindle,
                safe_z,
                verify_samples,
                facets,
                optimise,
                alpha,
                spread,
                output,
                report,
                mesh: args,
            } => {
                let options = crate::plan::options(crate::plan::Args {
                    part: &part,
                    radius,
                    scallop,
                    axes,
                    lead,
                    tilt,
                    post: &post,
                    origin: &origin,
                    direction: &direction,
                    cut: &cut,
                    feed,
                    plunge_feed,
                    spindle,
                    safe_z,
                    verify_samples,
                    facets: &facets,
                    optimise: &optimise,
                    alpha,
                    spread: &spread,
                })?;
                let (gcode, json) = crate::plan::run(&part, &args.options(), &args.step_options()?, &options)?;
                write(&output, gcode.as_bytes())?;
                if let Some(report) = report {
                    write(&report, json.as_bytes())?;
                }
                Ok(())
            }
            Command::Flank { args, mesh: m } => {
                let (program, json) = crate::flank::run(&args, &m.options(), &m.step_options()?)?;
                write(&args.output, program.as_bytes())?;
                if let Some(report) = &args.report {
                    write(report, json.as_bytes())?;
                }
                Ok(())
            }
            Command::Coons { args, mesh: m } => {
                let (program, json) = crate::coons::run(&args, &m.options(), &m.step_options()?)?;
                write(&args.output, program.as_bytes())?;
                if let Some(report) = &args.report {
                    write(report, json.as_bytes())?;
                }
                Ok(())
            }
            Command::Fixture { list: true, .. } => {
                fixtures::NAMES.iter().for_each(|n| println!("{n}"));
                fixtures::FLANK_NAMES.iter().for_each(|n| println!("{n}  (a flank-milling surface)"));
                println!("gen:SEED[:FACES]  (a generated part: outline, relief, holes and meshing drawn from SEED)");
                println!("panel:EDGE_MM     (the 120 × 80 mm panel with six holes: 0.75 ≈ 40k faces, 0.275 ≈ 300k)");
                fixtures::step::NAMES.iter().for_each(|n| println!("step:{n}  (a STEP file of exact faces)"));
                Ok(())
            }
            Command::Fixture { name, output, .. } => {
                let (name, output) = (name.expect("required by clap"), output.expect("required by clap"));
                if let Some(step_name) = name.strip_prefix("step:") {
                    let text = fixtures::step::by_name(step_name).ok_or_else(|| {
                        format!("unknown STEP fixture `{step_name}`; known: {}", fixtures::step::NAMES.join(", "))
                    })?;
                    return write(&output, text.as_bytes());
                }
                let mesh = fixtures::by_name(&name).ok_or_else(|| {
                    format!(
                        "unknown fixture `{name}`; known: {}, gen:SEED[:FACES], panel:EDGE_MM",
                        fixtures::NAMES.join(", ")
                    )
                })?;
                write(&output, &mesh::stl::write_binary(&mesh, &format!("slitpath fixture {name}")))
            }
        }
    }

    fn write(path: &std::path::Path, bytes: &[u8]) -> Result<(), String> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
        }
        std::fs::write(path, bytes).map_err(|e| format!("cannot write {}: {e}", path.display()))
    }

    fn print_report(name: &str, r: &mesh::MeshReport) {
        println!("{name}");
        print_figures("", r);
        if let Some(m) = &r.machined {
            println!("machined top surface:");
            print_figures("  ", m);
        }
        if let Some(note) = crate::plan::handle_note(r) {
            println!("{note}");
        }
    }

    fn print_figures(indent: &str, r: &mesh::MeshReport) {
        let [lo, hi] = r.bbox;
        println!("{indent}vertices {}, faces {}, edges {}, components {}", r.vertices, r.faces, r.edges, r.components);
        println!(
            "{indent}boundary loops {} {:?}, Euler characteristic {}, genus {}, closed {}",
            r.boundary_loops, r.loop_vertex_counts, r.euler_characteristic, r.genus, r.closed
        );
        println!(
            "{indent}area {:.6} mm², bbox [{:.4}, {:.4}, {:.4}] → [{:.4}, {:.4}, {:.4}]",
            r.area_mm2, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]
        );
        println!(
            "{indent}dropped: {} degenerate, {} duplicate faces; {} pinch vertices split; {} faces re-oriented; {} faces in other components",
            r.degenerate_faces_dropped, r.duplicate_faces_dropped, r.pinch_vertices_split, r.faces_reoriented, r.faces_in_other_components
        );
    }
}

#[cfg(not(target_arch = "wasm32"))]
fn main() {
    // The run is on a thread of the pool (with the main thread's stack size): the stages'
    // parallel parts then share work with the other threads directly, instead of each waking
    // the pool from outside and waiting (40-60 ms of a 40k-face plan).
    let _ = rayon::ThreadPoolBuilder::new().stack_size(8 << 20).build_global();
    if let Err(message) = rayon::scope(|_| cli::run()) {
        eprintln!("slitpath: error: {message}");
        std::process::exit(1);
    }
}

#[cfg(target_arch = "wasm32")]
fn main() {}
