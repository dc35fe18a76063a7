//! `slitpath` — the native command-line planner.
//!
//! Subcommands:
//! - `info PART.stl [--json]`: the mesh report (topology, boundary loops, machined top surface).
//! - `fixture NAME -o FILE.stl`: writes one of the analytic test surfaces as binary STL.
//!
//! Errors go to stderr as one line and the exit code is non-zero; no panic reaches the user.

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
        /// Writes an analytic test surface as binary STL.
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
        #[arg(long, value_parser = parse_vec3, default_value = "0,0,1")]
        axis: [f64; 3],
        /// Closed solids: faces within this angle of the tool axis form the machined top, degrees.
        #[arg(long, default_value_t = mesh::MeshOptions::default().wall_angle_deg)]
        wall_angle: f64,
        /// Maximum number of triangles accepted.
        #[arg(long, default_value_t = mesh::MeshOptions::default().max_triangles)]
        max_triangles: usize,
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
                let bytes = std::fs::read(&part).map_err(|e| format!("cannot read {}: {e}", part.display()))?;
                let out = mesh::load(&bytes, &args.options()).map_err(|e| format!("{}: {e}", part.display()))?;
                if json {
                    println!("{}", serde_json::to_string(&out.report).map_err(|e| e.to_string())?);
                } else {
                    print_report(&part.display().to_string(), &out.report);
                }
                Ok(())
            }
            Command::Fixture { list: true, .. } => {
                fixtures::NAMES.iter().for_each(|n| println!("{n}"));
                Ok(())
            }
            Command::Fixture { name, output, .. } => {
                let (name, output) = (name.expect("required by clap"), output.expect("required by clap"));
                let mesh = fixtures::by_name(&name)
                    .ok_or_else(|| format!("unknown fixture `{name}`; known: {}", fixtures::NAMES.join(", ")))?;
                let bytes = mesh::stl::write_binary(&mesh, &format!("slitpath fixture {name}"));
                if let Some(dir) = output.parent().filter(|d| !d.as_os_str().is_empty()) {
                    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
                }
                std::fs::write(&output, bytes).map_err(|e| format!("cannot write {}: {e}", output.display()))
            }
        }
    }

    fn print_report(name: &str, r: &mesh::MeshReport) {
        println!("{name}");
        print_figures("", r);
        if let Some(m) = &r.machined {
            println!("machined top surface:");
            print_figures("  ", m);
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
    if let Err(message) = cli::run() {
        eprintln!("slitpath: error: {message}");
        std::process::exit(1);
    }
}

#[cfg(target_arch = "wasm32")]
fn main() {}
