//! Fuzzing with the stable harness of `slitpath::fuzz` (issue 34): no input makes the core
//! panic. The bench command `cargo bench --bench fuzz` runs 10⁶ STL and 10³ planner cases.

use slitpath::fuzz;

#[test]
fn the_stl_reader_never_panics_on_mutated_files() {
    let summary = fuzz::fuzz_stl(1, 10_000);
    println!("{}", summary.format());
    assert_eq!(summary.panic_count, 0, "{}", summary.format());
    // The mutations reach both outcomes: files still read and files refused with a typed error.
    assert!(summary.accepted > 100 && summary.errors.values().sum::<usize>() > 1_000, "{}", summary.format());
    assert!(summary.errors.keys().any(|k| k.starts_with("truncated binary STL")), "{}", summary.format());
    assert!(summary.errors.keys().any(|k| k.starts_with("not a valid STL")), "{}", summary.format());
}

#[test]
fn the_planner_never_panics_on_faulty_meshes_and_options() {
    // A part in metres read as millimetres found the missing path-length guard (it ran on for
    // hours): `huge scale` is refused up front now.
    let (all, by_fault) = fuzz::fuzz_planner(1, 24);
    for (fault, s) in &by_fault {
        println!("{fault:<18} {}", s.format().replace('\n', "\n                   "));
    }
    assert_eq!(all.panic_count, 0, "{}", all.format());
    // Every fault kind ran twice; the benign ones (jitter, flipped faces) still plan.
    assert!(by_fault.values().all(|s| s.executions == 2));
    assert!(by_fault["flipped faces"].accepted == 2, "{}", by_fault["flipped faces"].format());
    assert!(all.accepted > 0 && all.errors.values().sum::<usize>() > 0, "{}", all.format());
}
