//! Shared helpers of the integration tests: where the shared meshes are, and LinuxCNC's
//! standalone G-code interpreter `rs274`.
//!
//! How it is run (LinuxCNC 2.9, Debian package `linuxcnc-uspace`): the program and a one-line
//! tool table are written to a fresh temporary directory, then
//! `rs274 -t tool.tbl -g program.ngc canon.txt` with stdin closed (`-g` = batch mode, no
//! prompts). rs274 writes the canonical machining calls (`STRAIGHT_FEED(x, y, z, a, b, c)`,
//! `STRAIGHT_TRAVERSE(…)`, `COMMENT("…")`, …) to `canon.txt`, prints `executing` and any error
//! to stderr, and exits with status 1 on an error. Without an INI file the default interpreter
//! accepts A B C words. The tool table's units are inches (no INI), so only T/P matter here.

#![allow(dead_code)]

use glam::DVec3;
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// One motion of rs274's canonical output.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Motion {
    /// STRAIGHT_TRAVERSE (G0) rather than STRAIGHT_FEED (G1).
    pub rapid: bool,
    pub xyz: DVec3,
    /// A, B, C in degrees.
    pub abc: DVec3,
    /// The feed rate in force (SET_FEED_RATE), mm/min.
    pub feed: f64,
}

/// What rs274 made of a program.
#[derive(Clone, Debug, Default)]
pub struct Interpreted {
    pub motions: Vec<Motion>,
    pub comments: Vec<String>,
    /// MESSAGE, LOG and other active-comment calls (must stay empty for our programs).
    pub active_comments: Vec<String>,
    /// Every canonical call, one a line.
    pub canon: String,
}

/// `../shared/meshes` beside the main checkout; a clone elsewhere uses the machine's copy.
pub fn shared_mesh_dir() -> PathBuf {
    let beside = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/meshes");
    if beside.is_dir() {
        beside
    } else {
        PathBuf::from("/work/shared/meshes")
    }
}

static RUN: AtomicUsize = AtomicUsize::new(0);
static RS274: Mutex<()> = Mutex::new(());

/// Runs `program` through rs274 with tool `tool_number` in the tool table and asserts that it
/// is accepted: exit status 0 and nothing on stderr but rs274's `executing`. Fails (panics) with
/// a pointer to scripts/setup.sh if rs274 is not installed — never passes silently.
pub fn rs274(program: &str, tool_number: u32) -> Interpreted {
    let dir: PathBuf = std::env::temp_dir().join(format!(
        "slitpath-rs274-{}-{}",
        std::process::id(),
        RUN.fetch_add(1, Ordering::Relaxed)
    ));
    std::fs::create_dir_all(&dir).expect("create a temporary directory for rs274");
    std::fs::write(dir.join("program.ngc"), program).expect("write program.ngc");
    std::fs::write(dir.join("tool.tbl"), format!("T{tool_number} P{tool_number} Z0 D0.25 ;ball-end\n"))
        .expect("write tool.tbl");
    // One rs274 at a time, and a run killed by a signal is run again (twice now, from the gcode
    // tests' parallel threads, rs274 died of one with no output at all); a rejection never is.
    let _one = RS274.lock().unwrap_or_else(|e| e.into_inner());
    let mut attempts = 0;
    let output = loop {
        attempts += 1;
        let output = match Command::new("rs274")
            .args(["-t", "tool.tbl", "-g", "program.ngc", "canon.txt"])
            .current_dir(&dir)
            .stdin(Stdio::null())
            .output()
        {
            Ok(o) => o,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => panic!(
                "rs274 (LinuxCNC's standalone G-code interpreter, Debian package linuxcnc-uspace) is not \
                 installed: run scripts/setup.sh (the CI installs it)"
            ),
            Err(e) => panic!("cannot run rs274: {e}"),
        };
        if output.status.code().is_some() || attempts == 3 {
            break output;
        }
        eprintln!("rs274 was killed by a signal ({:?}); running it again", output.status);
    };
    let stderr = String::from_utf8_lossy(&output.stderr).to_string();
    let errors: Vec<&str> = stderr.lines().map(str::trim).filter(|l| !l.is_empty() && *l != "executing").collect();
    let canon = std::fs::read_to_string(dir.join("canon.txt")).unwrap_or_default();
    assert!(
        output.status.success() && errors.is_empty(),
        "rs274 rejected the program (status {:?}, files in {}):\n{}\n--- canonical calls ---\n{}",
        output.status.code(),
        dir.display(),
        errors.join("\n"),
        canon.lines().rev().take(8).collect::<Vec<_>>().join("\n")
    );
    let _ = std::fs::remove_dir_all(&dir);
    parse_canon(canon)
}

fn parse_canon(canon: String) -> Interpreted {
    let mut out = Interpreted::default();
    let mut feed = 0.0;
    for line in canon.lines() {
        // "   21 N..... STRAIGHT_TRAVERSE(1.0000, 2.0000, 10.0000, 0.0000, 0.0000, 0.0000)"
        let call = line.split_once("N..... ").map(|(_, c)| c.trim()).unwrap_or("");
        let (name, args) = match call.split_once('(') {
            Some((n, a)) => (n, a.strip_suffix(')').unwrap_or(a)),
            None => continue,
        };
        let numbers = || -> Vec<f64> { args.split(',').map(|v| v.trim().parse::<f64>().unwrap()).collect() };
        match name {
            "STRAIGHT_TRAVERSE" | "STRAIGHT_FEED" => {
                let v = numbers();
                out.motions.push(Motion {
                    rapid: name == "STRAIGHT_TRAVERSE",
                    xyz: DVec3::new(v[0], v[1], v[2]),
                    abc: DVec3::new(v[3], v[4], v[5]),
                    feed,
                });
            }
            "SET_FEED_RATE" => feed = numbers()[0],
            "COMMENT" => out.comments.push(args.trim_matches('"').to_string()),
            "MESSAGE" | "LOG" | "LOGOPEN" | "LOGAPPEND" | "LOGCLOSE" | "DEBUG" | "PRINT" => {
                out.active_comments.push(call.to_string())
            }
            _ => {}
        }
    }
    out.canon = canon;
    out
}
