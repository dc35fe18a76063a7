//! Verifier benchmark (native): 100k fresh samples (and every vertex) of a 40k-face wavy disk
//! under a dense path of parallel passes (43.6k segments). Prints figures; asserts nothing about
//! time. The machine may be shared, so the CPU time of this thread is printed beside wall time.

use slitpath::bench::{format_verify, run_verify, verify_case};
use std::time::Instant;

/// CPU time of this thread (user + system) from /proc, milliseconds (10 ms ticks on Linux).
fn thread_cpu_ms() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/thread-self/stat").ok()?;
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = stat.rsplit_once(')')?.1;
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks * 10.0)
}

fn main() {
    let (surface, passes) = verify_case().expect("valid case");
    let start = Instant::now();
    let now = || start.elapsed().as_secs_f64() * 1e3;
    let runs = 5;
    let cpu0 = thread_cpu_ms();
    let figures: Vec<_> =
        (0..runs).map(|_| run_verify(&surface, &passes, 100_000, &now).expect("verifiable")).collect();
    let cpu = thread_cpu_ms().zip(cpu0).map(|(b, a)| (b - a) / runs as f64);
    let best = figures.iter().min_by(|a, b| a.verify_ms.total_cmp(&b.verify_ms)).expect("runs");
    println!("native, best of {runs} (wall clock): {}", format_verify(best));
    if let Some(cpu) = cpu {
        println!("native, CPU time per run (hierarchy built twice: once timed alone, once inside verify): {cpu:.0} ms");
    }
}
