//! `cargo bench --bench fuzz`: the STL reader on 10⁶ mutated files and the planner on 10³
//! faulty meshes and options (`slitpath::fuzz`); prints the outcomes by kind and every panic
//! with the case that reproduces it. `SLITPATH_FUZZ_STL` and `SLITPATH_FUZZ_PLANS` change the
//! counts.

use std::time::Instant;

fn count(var: &str, default: usize) -> usize {
    std::env::var(var).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

fn main() {
    let (stl, plans) = (count("SLITPATH_FUZZ_STL", 1_000_000), count("SLITPATH_FUZZ_PLANS", 1_000));
    let t = Instant::now();
    let summary = slitpath::fuzz::fuzz_stl(2026, stl);
    println!("fuzz: STL reader (seed 2026), {:.1} s\n{}", t.elapsed().as_secs_f64(), summary.format());
    let t = Instant::now();
    let (all, by_fault) = slitpath::fuzz::fuzz_planner(2026, plans);
    println!("\nfuzz: planner on faulty meshes (seed 2026), {:.1} s\n{}", t.elapsed().as_secs_f64(), all.format());
    for (fault, s) in &by_fault {
        println!("  {fault:<18} {} executions, {} planned, {} panics", s.executions, s.accepted, s.panic_count);
    }
}
