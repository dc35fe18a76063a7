//! Flank benchmark (native, issue 35): the blade at seed 002 Fig. 17's scale, 10 strips × 20
//! poses × 30 samples per axis, planned whole (guiding curves, optimisation, program, flank
//! verifier). The case is in `slitpath::bench` so the wasm benchmark runs the same one. Prints
//! figures (best of 3 by the optimisation's time); asserts nothing about time.

use slitpath::bench::{format_flank, run_flank};
use std::time::Instant;

fn main() {
    let start = Instant::now();
    let now = || start.elapsed().as_secs_f64() * 1e3;
    let best = (0..3)
        .map(|_| run_flank(&now).expect("the flank case plans"))
        .min_by(|a, b| a.optimise_ms.total_cmp(&b.optimise_ms))
        .expect("three runs");
    println!("native, best of 3: {}", format_flank(&best));
}
