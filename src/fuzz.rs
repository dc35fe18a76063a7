//! A stable-toolchain fuzzing harness: the STL reader on mutated bytes and the whole planner on
//! mutated meshes and options, every run under `catch_unwind`. Used by `tests/fuzz.rs` (small
//! counts, in `npm test`) and `benches/fuzz.rs` (10⁶ STL and 10³ planner executions).
//!
//! Why not `cargo fuzz`: it needs a nightly toolchain and `npm test` runs on stable. The
//! mutators here are structure-aware where it matters (the binary count field, f32 coordinates,
//! ASCII keywords and numbers, and on meshes the faults real files have: jitter, duplicated,
//! flipped and dropped faces, slivers, pinched rims, extreme scales, NaN), which reaches deeper
//! than blind bit flips in the few executions a test can afford.
//!
//! Invariant checked: no input makes the core panic. Every outcome is `Ok` or a typed error;
//! [`FuzzSummary`] counts them by message kind and keeps the first panics with the case that
//! reproduces them (`seed`, `case`).
//!
//! Deterministic: case `k` of seed `s` is the same input on every run ([`SplitMix64`]).

use crate::fixtures::{self, generated, SplitMix64};
use crate::mesh::{self, stl, MeshOptions, TriMesh};
use crate::plan::{PlanOptions, Planner};
use glam::DVec3;
use std::collections::BTreeMap;
use std::panic::{self, AssertUnwindSafe};

/// What a fuzzing run met.
#[derive(Debug, Default, Clone)]
pub struct FuzzSummary {
    pub executions: usize,
    pub accepted: usize,
    /// Typed errors by their kind (the message up to its first digit or colon).
    pub errors: BTreeMap<String, usize>,
    /// The panics: `(case, message)`, the first few only.
    pub panics: Vec<(usize, String)>,
    pub panic_count: usize,
}

/// One execution's outcome.
enum Outcome {
    Accepted,
    Error(String),
    Panic(String),
}

/// Runs `f`, catching a panic.
fn run<T, E: std::fmt::Display>(f: impl FnOnce() -> Result<T, E>) -> Outcome {
    match panic::catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(_)) => Outcome::Accepted,
        Ok(Err(e)) => Outcome::Error(e.to_string()),
        Err(payload) => Outcome::Panic(
            payload
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "(no message)".into()),
        ),
    }
}

impl FuzzSummary {
    fn record(&mut self, case: usize, outcome: &Outcome) {
        self.executions += 1;
        match outcome {
            Outcome::Accepted => self.accepted += 1,
            Outcome::Error(e) => *self.errors.entry(kind(e)).or_default() += 1,
            Outcome::Panic(message) => {
                self.panic_count += 1;
                if self.panics.len() < 8 {
                    self.panics.push((case, message.clone()));
                }
            }
        }
    }

    /// A few lines: executions, accepted, errors by kind, panics.
    pub fn format(&self) -> String {
        let mut s = format!(
            "{} executions: {} accepted, {} typed errors, {} panics",
            self.executions,
            self.accepted,
            self.errors.values().sum::<usize>(),
            self.panic_count
        );
        for (k, n) in &self.errors {
            s.push_str(&format!("\n  {n:>8}  {k}"));
        }
        for (case, message) in &self.panics {
            s.push_str(&format!("\n  PANIC case {case}: {message}"));
        }
        s
    }
}

/// The message's kind: its text before the first digit, quote or parenthesis, so errors that
/// differ only in the index at fault count together.
fn kind(message: &str) -> String {
    let end = message.find(|c: char| c.is_ascii_digit() || c == '`' || c == '(' || c == '[').unwrap_or(message.len());
    message[..end].trim_end().to_string()
}

/// Runs `f` with the panic message printing silenced (the summary keeps them).
fn quietly<R>(f: impl FnOnce() -> R) -> R {
    let hook = panic::take_hook();
    panic::set_hook(Box::new(|_| {}));
    let r = f();
    panic::set_hook(hook);
    r
}

/// The STL files the byte mutator starts from: small binary and ASCII parts (a disk, an
/// annulus, a holed plate), so that a million executions take seconds.
fn stl_corpus() -> Vec<Vec<u8>> {
    let disk = fixtures::unit_disk(3);
    let annulus = fixtures::concentric_annulus(0.4, 3);
    let holed = generated::part(7, 300..=400).mesh;
    vec![
        stl::write_binary(&disk, "disk"),
        stl::write_ascii(&disk, "disk").into_bytes(),
        stl::write_binary(&annulus, "annulus"),
        stl::write_ascii(&annulus, "annulus").into_bytes(),
        stl::write_binary(&holed, "holed"),
    ]
}

/// Case `case` of seed `seed`: one base file with one to four mutations.
pub fn mutated_stl(corpus: &[Vec<u8>], seed: u64, case: usize) -> Vec<u8> {
    let mut rng = SplitMix64::skipped(seed, case as u64 * 64);
    let mut bytes = corpus[below(&mut rng, corpus.len())].clone();
    for _ in 0..1 + below(&mut rng, 4) {
        mutate_bytes(&mut bytes, &mut rng);
    }
    bytes
}

fn below(rng: &mut SplitMix64, n: usize) -> usize {
    (rng.next_u64() % n.max(1) as u64) as usize
}

const F32_SPECIALS: [f32; 8] = [f32::NAN, f32::INFINITY, -f32::INFINITY, f32::MAX, 1e-42, 0.0, -0.0, 3.0e38];
const TOKENS: [&[u8]; 10] =
    [b"solid", b"facet", b"normal", b"outer", b"loop", b"vertex", b"endloop", b"endfacet", b"endsolid", b"nan"];

fn mutate_bytes(bytes: &mut Vec<u8>, rng: &mut SplitMix64) {
    let n = bytes.len();
    match below(rng, 10) {
        // Bit flips.
        0 if n > 0 => {
            for _ in 0..1 + below(rng, 8) {
                let i = below(rng, n);
                bytes[i] ^= 1 << below(rng, 8);
            }
        }
        // A byte set to a boundary value.
        1 if n > 0 => {
            let i = below(rng, n);
            bytes[i] = [0x00, 0xFF, 0x7F, 0x80, b'\n', b' ', b'-', b'e'][below(rng, 8)];
        }
        // A binary coordinate (or any aligned word) replaced by a special float.
        2 if n >= 88 => {
            let i = 84 + 4 * below(rng, (n - 84) / 4);
            let v = F32_SPECIALS[below(rng, F32_SPECIALS.len())];
            if i + 4 <= n {
                bytes[i..i + 4].copy_from_slice(&v.to_le_bytes());
            }
        }
        // The binary triangle count rewritten: off by one, huge, zero.
        3 if n >= 84 => {
            let old = u32::from_le_bytes(bytes[80..84].try_into().expect("4 bytes"));
            let new = [old.wrapping_add(1), old.wrapping_sub(1), u32::MAX, 0, 1, old.wrapping_mul(2)][below(rng, 6)];
            bytes[80..84].copy_from_slice(&new.to_le_bytes());
        }
        // Truncated.
        4 => bytes.truncate(below(rng, n + 1)),
        // A chunk deleted or duplicated.
        5 if n > 0 => {
            let a = below(rng, n);
            let b = (a + 1 + below(rng, 64)).min(n);
            if rng.unit() < 0.5 {
                bytes.drain(a..b);
            } else {
                let chunk = bytes[a..b].to_vec();
                let at = below(rng, n + 1);
                bytes.splice(at..at, chunk);
            }
        }
        // An ASCII keyword inserted or overwritten.
        6 => {
            let token = TOKENS[below(rng, TOKENS.len())];
            let at = below(rng, n + 1);
            if rng.unit() < 0.5 || at + token.len() > n {
                bytes.splice(at..at, token.iter().copied());
            } else {
                bytes[at..at + token.len()].copy_from_slice(token);
            }
        }
        // An ASCII number replaced by an extreme or malformed one.
        7 => {
            let digits =
                bytes.iter().enumerate().filter(|(_, b)| b.is_ascii_digit()).map(|(i, _)| i).nth(below(rng, 4096));
            if let Some(i) = digits {
                let text: &[u8] =
                    [&b"1e400"[..], b"-0", b"nan", b"inf", b"1.2.3", b"9999999999999999999999", b"--1"][below(rng, 7)];
                let end = (i + 1..bytes.len()).find(|&j| !bytes[j].is_ascii_digit()).unwrap_or(bytes.len());
                bytes.splice(i..end, text.iter().copied());
            }
        }
        // Random garbage appended or the file replaced by garbage.
        8 => {
            let len = below(rng, 256);
            let garbage: Vec<u8> = (0..len).map(|_| rng.next_u64() as u8).collect();
            if rng.unit() < 0.8 {
                bytes.extend(garbage);
            } else {
                *bytes = garbage;
            }
        }
        // Whitespace only, or the header alone.
        _ => {
            let keep = if rng.unit() < 0.5 { 0 } else { n.min(84) };
            bytes.truncate(keep);
            bytes.extend(std::iter::repeat(b' ').take(below(rng, 8)));
        }
    }
}

/// `cases` mutated STL files of seed `seed` read by [`mesh::load`] with the default options.
pub fn fuzz_stl(seed: u64, cases: usize) -> FuzzSummary {
    let corpus = stl_corpus();
    let options = MeshOptions { max_triangles: 100_000, ..MeshOptions::default() };
    let mut summary = FuzzSummary::default();
    quietly(|| {
        for case in 0..cases {
            let bytes = mutated_stl(&corpus, seed, case);
            summary.record(case, &run(|| mesh::load(&bytes, &options)));
        }
    });
    summary
}

/// The mesh faults the planner is fed, one per case.
const MESH_FAULTS: [&str; 12] = [
    "jitter",
    "duplicated faces",
    "flipped faces",
    "dropped faces",
    "slivers",
    "pinched rim",
    "tiny scale",
    "huge scale",
    "far offset",
    "NaN vertex",
    "degenerate faces",
    "bad options",
];

/// A generated part of a few hundred to a thousand faces with one fault of [`MESH_FAULTS`]
/// (by `case`), and the plan options it is planned with.
pub fn mutated_part(seed: u64, case: usize) -> (TriMesh, PlanOptions, &'static str) {
    let mut rng = SplitMix64::skipped(seed ^ 0xF0221, case as u64 * 64);
    let part =
        generated::part(seed.wrapping_mul(1000).wrapping_add(case as u64 / MESH_FAULTS.len() as u64), 400..=1200);
    let mut mesh = part.mesh;
    let mut options = PlanOptions {
        radius_mm: part.spec.radius_mm,
        // A coarse h keeps a case to tens of milliseconds; the faults, not the finish, are tested.
        scallop_mm: 0.05,
        verify_samples: 2_000,
        ..PlanOptions::default()
    };
    let fault = MESH_FAULTS[case % MESH_FAULTS.len()];
    let nt = mesh.triangles.len();
    let nv = mesh.positions.len();
    let some = |rng: &mut SplitMix64, n: usize| 1 + below(rng, n);
    match fault {
        "jitter" => {
            let amount = [1e-9, 1e-3, 0.3, 3.0][below(&mut rng, 4)];
            for p in &mut mesh.positions {
                *p += amount * DVec3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5);
            }
        }
        "duplicated faces" => {
            for _ in 0..some(&mut rng, 4) {
                let t = mesh.triangles[below(&mut rng, nt)];
                mesh.triangles.push(if rng.unit() < 0.5 { t } else { [t[0], t[2], t[1]] });
            }
        }
        "flipped faces" => {
            for _ in 0..some(&mut rng, 6) {
                let t = &mut mesh.triangles[below(&mut rng, nt)];
                t.swap(1, 2);
            }
        }
        "dropped faces" => {
            for _ in 0..some(&mut rng, 40) {
                let n = mesh.triangles.len();
                if n > 1 {
                    mesh.triangles.swap_remove(below(&mut rng, n));
                }
            }
        }
        "slivers" => {
            // A vertex moved onto the midpoint of an opposite edge: zero-area and needle faces.
            for _ in 0..some(&mut rng, 8) {
                let [a, b, c] = mesh.triangles[below(&mut rng, nt)];
                let t = [1e-9, 1e-4, 0.5][below(&mut rng, 3)];
                mesh.positions[a as usize] = mesh.positions[b as usize].lerp(mesh.positions[c as usize], t);
            }
        }
        "pinched rim" => {
            // Two far-apart vertices merged: a bow-tie or a pinched boundary.
            for _ in 0..some(&mut rng, 2) {
                let (a, b) = (below(&mut rng, nv) as u32, below(&mut rng, nv) as u32);
                for t in &mut mesh.triangles {
                    for i in t.iter_mut() {
                        if *i == b {
                            *i = a;
                        }
                    }
                }
            }
        }
        "tiny scale" | "huge scale" => {
            let s = if fault == "tiny scale" {
                [1e-3, 1e-6, 1e-12][below(&mut rng, 3)]
            } else {
                [1e3, 1e6][below(&mut rng, 2)]
            };
            for p in &mut mesh.positions {
                *p *= s;
            }
        }
        "far offset" => {
            let d = [1e4, 1e7, 1e9][below(&mut rng, 3)];
            for p in &mut mesh.positions {
                *p += DVec3::splat(d);
            }
        }
        "NaN vertex" => {
            let v = below(&mut rng, nv);
            mesh.positions[v].x = [f64::NAN, f64::INFINITY, 1e300][below(&mut rng, 3)];
        }
        "degenerate faces" => {
            for _ in 0..some(&mut rng, 6) {
                let t = &mut mesh.triangles[below(&mut rng, nt)];
                t[1] = t[0];
            }
        }
        _ => {
            let bad = [f64::NAN, 0.0, -1.0, f64::INFINITY, 1e-300, 1e300];
            let x = bad[below(&mut rng, bad.len())];
            match below(&mut rng, 5) {
                0 => options.radius_mm = x,
                1 => options.scallop_mm = x,
                2 => options.alpha = x,
                3 => options.feed_mm_min = x,
                _ => options.safe_z_mm = Some(x),
            }
        }
    }
    (mesh, options, fault)
}

/// `cases` mutated parts of seed `seed` through the whole planner, from STL bytes (so the
/// reader's f32 rounding is part of it) to the verified G-code.
pub fn fuzz_planner(seed: u64, cases: usize) -> (FuzzSummary, BTreeMap<&'static str, FuzzSummary>) {
    fuzz_planner_range(seed, 0..cases)
}

/// [`fuzz_planner`] on the cases `cases` only (to reproduce one).
pub fn fuzz_planner_range(
    seed: u64,
    cases: std::ops::Range<usize>,
) -> (FuzzSummary, BTreeMap<&'static str, FuzzSummary>) {
    let mut all = FuzzSummary::default();
    let mut by_fault: BTreeMap<&'static str, FuzzSummary> = BTreeMap::new();
    quietly(|| {
        for case in cases.clone() {
            let (mesh, options, fault) = mutated_part(seed, case);
            let bytes = stl::write_binary(&mesh, "fuzz");
            let outcome = run(|| -> Result<(), String> {
                let out = mesh::load(&bytes, &MeshOptions::default()).map_err(|e| e.to_string())?;
                let planner = Planner::new(out, &|| 0.0).map_err(|e| e.to_string())?;
                planner.plan(&options, &mut |_, _, _| {}, &|| 0.0).map_err(|e| e.to_string())?;
                Ok(())
            });
            by_fault.entry(fault).or_default().record(case, &outcome);
            all.record(case, &outcome);
        }
    });
    (all, by_fault)
}
