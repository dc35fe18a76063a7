//! slitpath — spiral finishing toolpaths for ball-end milling of freeform surfaces with holes.
//!
//! The planning core is a pipeline of pure stages (see `DESIGN.md` in the shared folder and the
//! seed paper 000, "conformal slit mapping"): each stage is one module with an options struct, a
//! typed error and plain output data. The core has no I/O and knows nothing about the browser:
//! `wasm` is a thin facade compiled only for `wasm32`, the CLI lives in `src/bin/`.
//!
//! | stage | module | status |
//! |---|---|---|
//! | STL → welded, validated surface | [`mesh`] | implemented |
//! | analytic test surfaces | [`fixtures`] | implemented |
//! | conformal flattening S → S^F (BFF) | [`flatten`] | implemented |
//! | conformal slit map S^F → disk/annulus with slits, inverse map | [`slitmap`] | implemented |
//! | sparse Cholesky, cotan Laplacian (shared kernel) | [`linalg`] | implemented |
//! | contact points → ball centres, tool tips and axes, lead-in/out | [`toolpath`] | implemented |
//! | posts: LinuxCNC, GRBL, 5-axis A/C, APT CL data | [`gcode`] | implemented |

pub mod bench;
pub mod fixtures;
pub mod flatten;
pub mod gcode;
pub mod linalg;
pub mod mesh;
pub mod num;
pub mod slitmap;
pub mod toolpath;

#[cfg(target_arch = "wasm32")]
pub mod wasm;
