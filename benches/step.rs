//! STEP benchmark (native, issue 36): a 20-face file and the blade band read and tessellated
//! (best of 3), and seed 004's band spiral over the blade band with the CLI's defaults. The
//! cases are in `slitpath::bench::step` so the wasm benchmark runs the same ones. Prints
//! figures; asserts nothing about time.

use slitpath::bench::step::{format_step, run_coons_band, run_step, step_cases};
use std::time::Instant;

fn main() {
    let start = Instant::now();
    let now = || start.elapsed().as_secs_f64() * 1e3;
    for (name, text) in step_cases() {
        println!("native, best of 3: {}", format_step(&run_step(name, &text, 3, &now).expect("the STEP case reads")));
    }
    println!("native: {}", run_coons_band(&now).expect("the blade band plans"));
}
