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
//! | STEP → exact faces → face-tagged surface | [`step`] | implemented |
//! | analytic test surfaces | [`fixtures`] | implemented |
//! | conformal flattening S → S^F (BFF) | [`flatten`] | implemented |
//! | conformal slit map S^F → disk/annulus with slits, inverse map | [`slitmap`] | implemented |
//! | optimal pole: scallop-uniformity energy E_min and its minimisation | [`origin`] | implemented |
//! | scalar-field optimisation (seed 003): rings that follow the surface | [`optimise`] | implemented |
//! | ring radii with the scallop height under control | [`spacing`] | implemented |
//! | rings bridged into one spiral around the holes | [`spiral`] | implemented |
//! | ball centres, tool tips and axes, lead-in/out | [`toolpath`] | implemented |
//! | G-code posts (LinuxCNC, GRBL, A/C 5-axis) and CL data | [`gcode`] | implemented |
//! | flank strategy (seed 002): conical tool, G¹ multi-strip paths | [`flank`] | implemented |
//! | band spiral over four-sided STEP faces (seed 004): Coons reparameterisation | [`coons`] | implemented |
//! | scallop simulation of the final path | [`verify`] | implemented |
//! | the whole pipeline, stage by stage | [`plan`] | implemented |
//! | sparse Cholesky, cotan Laplacian (shared kernel) | [`linalg`] | implemented |
//! | deterministic transcendental functions | [`num`] | implemented |

pub mod bench;
mod bvh;
pub mod coons;
pub mod fixtures;
pub mod flank;
pub mod flatten;
mod flip;
pub mod fuzz;
pub mod gcode;
mod hash;
pub mod linalg;
pub mod mesh;
pub mod num;
pub mod optimise;
pub mod origin;
mod par;
pub mod plan;
pub mod slitmap;
pub mod spacing;
pub mod spiral;
pub mod spread;
pub mod step;
pub mod toolpath;
pub mod verify;

#[cfg(target_arch = "wasm32")]
pub mod wasm;
