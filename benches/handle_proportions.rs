//! Which handle proportions plan (issue 34 item 4, docs/known-limits.md): one bridge over a pair
//! of holes ([`slitpath::fixtures::handles::plate_with_bridge`]) of a range of widths and spans (10 mm high),
//! cut in the middle of its neck and planned with R 2 mm, h 0.05 mm (the CLI's defaults
//! otherwise), then the two fixtures with handles. Prints one row per part; asserts nothing.
//!
//! `SLITPATH_HANDLES=W:S:H[:EDGE],…` plans bridges of width W, holes' far sides at ±S and height
//! H (mm) instead; `SLITPATH_HANDLES_H=h` another scallop limit; `SLITPATH_HANDLES_STL=DIR` also
//! writes each bridge's part there (`DIR/bridge-W-S-H-EDGE.stl`) to plan it with the CLI.

use slitpath::fixtures::{self, handles::Bridge};
use slitpath::mesh::{self, MeshOptions, TriMesh};
use slitpath::plan::{PlanOptions, Planner};
use std::time::Instant;

#[global_allocator]
static ALLOC: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// A bridge `width` wide landing at x = ±`span`, `height` high, over holes from x = ±span/2 to
/// ±span, 5 mm wider than it (the fixtures' shape: the bridge is `height`/2 above the plate
/// between the holes, where a ball of 2 mm must pass under it).
fn bridge(width: f64, span: f64, height: f64) -> Bridge {
    Bridge {
        y_mm: 0.0,
        inner_mm: 0.5 * span,
        outer_mm: span,
        hole_half_mm: 0.5 * width + 2.5,
        half_width_mm: 0.5 * width,
        height_mm: height,
    }
}

fn main() {
    let start = Instant::now();
    let now = || start.elapsed().as_secs_f64() * 1e3;
    let h: f64 = std::env::var("SLITPATH_HANDLES_H").ok().and_then(|v| v.parse().ok()).unwrap_or(0.05);
    let mut cases: Vec<(String, TriMesh, f64)> = Vec::new();
    // 10:10:10 is an undercut (the ball does not fit under the steep bridge): the tool path
    // refuses it, whatever the cut.
    let spec = std::env::var("SLITPATH_HANDLES").unwrap_or_else(|_| {
        ["10:10:10", "5:14:10", "7:14:10", "10:14:10", "15:14:10", "5:20:10", "10:20:10", "15:20:10"]
            .into_iter()
            .chain(["5:28:10", "10:28:10", "15:28:10"])
            .collect::<Vec<_>>()
            .join(",")
    });
    for item in spec.split(',') {
        let v: Vec<f64> = item.split(':').filter_map(|x| x.parse().ok()).collect();
        if v.len() < 3 {
            eprintln!("skipped {item}: W:S:H[:EDGE] expected");
            continue;
        }
        let b = bridge(v[0], v[1], v[2]);
        let edge = v.get(3).copied().unwrap_or(fixtures::handles::HANDLE_EDGE_MM);
        let part = fixtures::handles::plate_with_bridge(&b, edge);
        if let Ok(dir) = std::env::var("SLITPATH_HANDLES_STL") {
            let path = std::path::Path::new(&dir).join(format!("bridge-{}-{}-{}-{edge}.stl", v[0], v[1], v[2]));
            std::fs::write(&path, slitpath::mesh::stl::write_binary(&part, "bridge")).expect("writable STL directory");
        }
        cases.push((format!("bridge {}x{:.1} H{} e{}", v[0], b.length_mm(), v[2], edge), part, b.length_mm() / v[0]));
    }
    for name in ["plate_with_handle", "genus2_sheet"] {
        let b = fixtures::handles::PLATE_BRIDGE;
        cases.push((
            name.to_string(),
            fixtures::by_name(name).expect("a fixture"),
            b.length_mm() / (2.0 * b.half_width_mm),
        ));
    }
    println!(
        "handles, R 2 mm, h {h} mm\n{:<28} {:>6} {:>8} {:>8} {:>8} {:>7} {:>8} {:>8} {:>9} {:>6} {:>6}",
        "part", "L/W", "cut mm", "short", "depth", "plan s", "max/h", "out/h", "uncov %", "gouge", "rings"
    );
    let _ = rayon::ThreadPoolBuilder::new().stack_size(8 << 20).build_global();
    rayon::scope(|_| {
        for (name, part, ratio) in &cases {
            let t0 = now();
            let result = mesh::from_triangles(part, &MeshOptions::default())
                .map_err(|e| e.to_string())
                .and_then(|out| Planner::new(out, &now).map_err(|e| e.to_string()))
                .and_then(|planner| {
                    let options = PlanOptions { radius_mm: 2.0, scallop_mm: h, ..PlanOptions::default() };
                    planner.plan(&options, &mut |_, _, _| {}, &now).map_err(|e| e.to_string())
                });
            let seconds = (now() - t0) / 1e3;
            match result {
                Ok(plan) => {
                    if let Ok(dir) = std::env::var("SLITPATH_HANDLES_STL") {
                        let path = std::path::Path::new(&dir).join(format!("{}.json", name.replace(' ', "_")));
                        let json = serde_json::to_string_pretty(&plan.report).expect("a report");
                        std::fs::write(path, json).expect("writable report directory");
                    }
                    let v = plan.verification().expect("verified");
                    let cuts = &plan.report.mesh.handle_cuts;
                    let list = |f: &dyn Fn(&mesh::HandleCut) -> f64| {
                        cuts.iter().map(|c| format!("{:.2}", f(c))).collect::<Vec<_>>().join("/")
                    };
                    println!(
                        "{name:<28} {ratio:>6.2} {:>8} {:>8} {:>8} {seconds:>7.2} {:>8.3} {:>8.3} {:>9.4} {:>6} {:>6}",
                        list(&|c| c.length_mm),
                        list(&|c| c.shortest_mm),
                        list(&|c| c.depth_mm),
                        v.max_scallop_mm / h,
                        v.max_scallop_outside_valleys_mm / h,
                        100.0 * v.uncovered_fraction,
                        v.gouges,
                        plan.report.rings
                    );
                }
                Err(e) => println!("{name:<28} {ratio:>6.2} cannot be planned ({seconds:.2} s): {e}"),
            }
        }
    });
}
