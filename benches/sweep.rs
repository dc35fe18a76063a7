//! Issue 34's planned-everywhere sweep (native): generated parts of seeds 0..200 (3k–12k faces,
//! [`SWEEP_FACES`]) planned with their own R and h and verified; prints one row per part, then
//! the failures grouped by the stage that failed (`finish`: planned, but the verified finish
//! breaks [`slitpath::bench::SWEEP_LIMITS`]). Asserts nothing.
//!
//! `SLITPATH_SWEEP_PARTS=N` sweeps N parts, `SLITPATH_SWEEP_SEEDS=3,40,…` those seeds only,
//! `SLITPATH_SWEEP_FACES=LO:HI` other face counts, `SLITPATH_SWEEP_REPORTS=DIR` writes each part's
//! STL and plan report (`DIR/genNNN.stl`, `.json`) there.

use slitpath::bench::{format_sweep, run_sweep, SWEEP_FACES};
use slitpath::fixtures::generated;
use std::collections::BTreeMap;
use std::time::Instant;

// The CLI's allocator (see src/bin/slitpath/main.rs), so the figures are the CLI's.
#[global_allocator]
static ALLOC: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() {
    let start = Instant::now();
    let now = || start.elapsed().as_secs_f64() * 1e3;
    let count: u64 = std::env::var("SLITPATH_SWEEP_PARTS").ok().and_then(|v| v.parse().ok()).unwrap_or(200);
    let faces = std::env::var("SLITPATH_SWEEP_FACES")
        .ok()
        .and_then(|v| {
            let (lo, hi) = v.split_once(':')?;
            Some(lo.parse().ok()?..=hi.parse().ok()?)
        })
        .unwrap_or(SWEEP_FACES);
    let _ = rayon::ThreadPoolBuilder::new().stack_size(8 << 20).build_global();
    rayon::scope(|_| {
        println!("planned-everywhere sweep, native: generated parts, {faces:?} faces");
        let mut failures: BTreeMap<&str, Vec<String>> = BTreeMap::new();
        let (mut planned, mut methods) = (0, BTreeMap::new());
        let mut lengths = Vec::new();
        let seeds: Vec<u64> = match std::env::var("SLITPATH_SWEEP_SEEDS") {
            Ok(list) => list.split(',').filter_map(|s| s.trim().parse().ok()).collect(),
            Err(_) => (0..count).collect(),
        };
        for seed in seeds {
            let part = generated::part(seed, faces.clone());
            match run_sweep(&part, 100_000, &now) {
                Ok(row) => {
                    if let Ok(dir) = std::env::var("SLITPATH_SWEEP_REPORTS") {
                        let path = std::path::Path::new(&dir).join(format!("gen{seed:03}"));
                        std::fs::write(
                            path.with_extension("stl"),
                            slitpath::mesh::stl::write_binary(&part.mesh, &part.name),
                        )
                        .expect("writes the part");
                        std::fs::write(path.with_extension("json"), serde_json::to_string_pretty(&row.report).unwrap())
                            .expect("writes the report");
                    }
                    println!("{}", format_sweep(&row));
                    lengths.push(row.length_over_ideal);
                    *methods.entry(format!("{:?}", row.flatten.method)).or_insert(0) += 1;
                    if row.within_limits() {
                        planned += 1;
                    } else {
                        failures.entry("finish").or_default().push(format!("{}: {}", row.name, row.finish()));
                    }
                }
                Err(f) => {
                    println!("{:<42} FAILED at {}: {}", f.name, f.stage, f.message);
                    failures.entry(f.stage).or_default().push(format!("{}: {}", f.name, f.message));
                }
            }
        }
        let failed: usize = failures.values().map(Vec::len).sum();
        println!("{planned} planned within the limits, {failed} failed; flattening methods {methods:?}");
        lengths.sort_by(f64::total_cmp);
        if !lengths.is_empty() {
            let mean = lengths.iter().sum::<f64>() / lengths.len() as f64;
            println!("length / ideal: median {:.4}, mean {:.4}", lengths[lengths.len() / 2], mean);
        }
        for (stage, list) in &failures {
            println!("  {stage}: {}", list.len());
            for f in list {
                println!("    {f}");
            }
        }
        println!("total {:.1} s", now() / 1e3);
    });
}
