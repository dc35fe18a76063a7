//! Issue 32's length table (native): generated parts planned with the conformal map's rings and
//! with seed 003's optimised field, each verified at its own R and h. The wasm twin
//! (tests/wasm_bench.rs) runs the first parts of the same list. Prints figures; asserts nothing.

use slitpath::bench::{format_length, length_parts, run_length, summarise_lengths, LENGTH_HEADER};
use std::time::Instant;

// The CLI's allocator (see src/bin/slitpath/main.rs), so the figures are the CLI's.
#[global_allocator]
static ALLOC: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() {
    let start = Instant::now();
    let now = || start.elapsed().as_secs_f64() * 1e3;
    // `SLITPATH_LENGTH_PARTS=200 cargo bench --bench length` sweeps more parts (default 25).
    let count = std::env::var("SLITPATH_LENGTH_PARTS").ok().and_then(|v| v.parse().ok()).unwrap_or(25);
    let _ = rayon::ThreadPoolBuilder::new().stack_size(8 << 20).build_global();
    rayon::scope(|_| {
        println!("path length at equal finish, native\n{LENGTH_HEADER}");
        let (mut rows, mut failed) = (Vec::new(), 0);
        for part in length_parts(count) {
            match run_length(&part, &now) {
                Ok(row) => {
                    println!("{}", format_length(&row));
                    rows.push(row);
                }
                Err(e) => {
                    println!("{:<42} cannot be planned: {e}", part.name);
                    failed += 1;
                }
            }
        }
        println!("{}", summarise_lengths(&rows, failed));
    });
}
