//! Stage 1 — `mesh`: STL bytes → one welded, validated, consistently oriented surface to machine.
//!
//! What it computes (DESIGN.md "mesh"):
//! 1. [`stl`]: binary or ASCII STL → triangle soup. Binary is decided by the size `84 + 50·n`,
//!    so a binary file whose header starts with `solid` is still read as binary.
//! 2. [`weld`]: coincident corners merged within a tolerance relative to the bounding-box
//!    diagonal, in O(n log n); degenerate (zero-area) and duplicate faces dropped and counted.
//! 3. [`topology`]: manifold check (an edge with more than two faces is an error naming it),
//!    pinch vertices split, consistent orientation (re-oriented when possible), connected
//!    components, ordered boundary loops, Euler characteristic and genus.
//! 4. The surface to plan: the largest open component (by area), oriented so its normals face
//!    the tool; or, for a closed solid, the machinable top surface ([`extract`]): faces whose
//!    outward normal is within the wall angle of the tool axis, largest component. Steep walls
//!    of bosses and pockets become holes.
//! 5. [`geometry`]: angle-weighted vertex normals and the per-face curvature tensor of
//!    Rusinkiewicz 2004 (seed 000 ref. [39]), needed by the scallop energy (seed 000 §2.3).
//! 6. [`refine`]: for the planner, more faces around each hole vertex and ears split (same
//!    geometry), so the slit map can open every hole into a slit without folding a triangle and
//!    every face has a corner off the boundary.
//!
//! 7. [`handles`]: a surface of genus g > 0 with a boundary is cut along g short non-separating
//!    loops into a disk with holes (two more per handle); the report lists the cuts.
//!
//! And a query structure the later stages share: [`nearest`], the nearest facet point of a 3D
//! point and a ball moved onto the mesh's offset surface (the toolpath keeps every ball centre
//! off the facets with it), and [`axial`], the facet point nearest to an axis within a slab
//! across it (the flank collision check's cylinders).
//!
//! Invariants of the output [`Surface`]: every edge has one or two faces, every vertex has a single
//! fan, faces are wound counter-clockwise seen from the tool side, `loops[0]` is the outer boundary
//! (the longest loop), and loops are ordered so the surface lies on their left seen from the tool
//! side (outer loop counter-clockwise, holes clockwise).
//!
//! Bad input never panics: every fault is a [`MeshError`] that names it.

pub mod axial;
pub mod creases;
pub mod extract;
pub mod geometry;
pub mod handles;
pub mod nearest;
pub mod quality;
pub mod refine;
pub mod stl;
pub mod topology;
pub mod weld;

use glam::DVec3;
use serde::Serialize;

pub use geometry::FaceCurvature;
pub use handles::{HandleCut, HandleError, HandleOptions};

/// Options of the mesh stage. `Default` gives the documented defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshOptions {
    /// Corners closer than this fraction of the bounding-box diagonal are welded. Default `1e-6`.
    pub weld_tolerance_rel: f64,
    /// Inputs with more triangles are refused before any allocation. Default 5 000 000.
    pub max_triangles: usize,
    /// Direction the tool comes from (unit vector, towards the tool). Default `+Z`.
    pub tool_axis: DVec3,
    /// For closed solids: faces whose outward normal is within this angle of the tool axis form
    /// the machined top surface; steeper faces are walls. Degrees. Default `80`.
    pub wall_angle_deg: f64,
    /// How handles are cut when the surface to plan has genus > 0 ([`handles`]).
    pub handles: HandleOptions,
}

impl Default for MeshOptions {
    fn default() -> Self {
        Self {
            weld_tolerance_rel: 1e-6,
            max_triangles: 5_000_000,
            tool_axis: DVec3::Z,
            wall_angle_deg: 80.0,
            handles: HandleOptions::default(),
        }
    }
}

/// An indexed triangle mesh: the plain interchange type of the stage (and of [`crate::fixtures`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    pub positions: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
}

/// The surface the planner machines, with its boundary and differential geometry.
#[derive(Clone, Debug)]
pub struct Surface {
    /// Vertex positions, millimetres.
    pub positions: Vec<DVec3>,
    /// Counter-clockwise seen from the tool side.
    pub triangles: Vec<[u32; 3]>,
    /// Boundary loops as vertex cycles; `loops[0]` is the outer one (the longest by length).
    pub loops: Vec<Vec<u32>>,
    /// Unit face normals, towards the tool side.
    pub face_normals: Vec<DVec3>,
    /// Face areas, mm².
    pub face_areas: Vec<f64>,
    /// Angle-weighted unit vertex normals, towards the tool side.
    pub vertex_normals: Vec<DVec3>,
    /// The normals the ball rides per face corner, where they differ from the vertex normals:
    /// split at sharp creases for exact facets ([`Surface::with_crease_normals`]); empty = the
    /// vertex normals.
    pub corner_normals: Vec<[DVec3; 3]>,
    /// Per-face curvature tensor (Rusinkiewicz 2004), 1/mm; positive where convex seen from the tool.
    pub curvature: Vec<FaceCurvature>,
}

impl Surface {
    /// Euler characteristic `V − E + F`.
    pub fn euler_characteristic(&self) -> i64 {
        topology::euler_characteristic(self.positions.len(), &self.triangles)
    }

    /// Genus from `χ = 2 − 2g − b` (the surface is one connected component).
    pub fn genus(&self) -> i64 {
        (2 - self.loops.len() as i64 - self.euler_characteristic()) / 2
    }

    /// The planner's precondition: a connected surface of genus 0 with at least one boundary
    /// loop (a disk with holes). [`load`] cuts the handles of a surface of genus > 0 first.
    pub fn check_plannable(&self) -> Result<(), MeshError> {
        if self.loops.is_empty() {
            return Err(MeshError::Closed);
        }
        let genus = self.genus();
        if genus != 0 {
            return Err(MeshError::HighGenus { genus, loops: self.loops.len() });
        }
        Ok(())
    }

    /// The normal of corner `k` of `face` the ball rides (see [`Surface::corner_normals`]).
    #[inline]
    pub fn corner_normal(&self, face: usize, k: usize) -> DVec3 {
        match self.corner_normals.get(face) {
            Some(c) => c[k],
            None => self.vertex_normals[self.triangles[face][k] as usize],
        }
    }

    /// How far a ball of radius `r` placed along a normal of `face` is moved out along it to
    /// clear the face's plane ([`ball_lift_mm`]), at most: the normals inside a face are
    /// normalised means of its corners', so none tilts more from the face's than theirs.
    pub fn face_lift_mm(&self, face: usize, r: f64) -> f64 {
        (0..3).map(|k| ball_lift_mm(self.corner_normal(face, k), self.face_normals[face], r)).fold(0.0, f64::max)
    }

    /// The unit normal at barycentric `bary` of `face`: the corner normals interpolated, the
    /// face normal where they cancel.
    pub fn normal_at(&self, face: usize, bary: [f64; 3]) -> DVec3 {
        let n = self.corner_normal(face, 0) * bary[0]
            + self.corner_normal(face, 1) * bary[1]
            + self.corner_normal(face, 2) * bary[2];
        let n = n.normalize_or_zero();
        if n == DVec3::ZERO {
            self.face_normals[face]
        } else {
            n
        }
    }

    /// This surface with the normals of its facets as they are: recomputed from the faces and
    /// split at creases turning more than `crease_deg` ([`geometry::crease_normals`]).
    pub fn with_crease_normals(&self, crease_deg: f64) -> Surface {
        let (vertex_normals, corner_normals) = geometry::crease_normals(self, crease_deg);
        Surface { vertex_normals, corner_normals, ..self.clone() }
    }

    /// The same surface with the tool on the other side: windings, loops, normals and
    /// curvatures reversed (an open surface whose side the mesh stage could not tell from the
    /// tool axis, such as a tube round it).
    pub fn flipped(&self) -> Surface {
        let neg = |v: &Vec<DVec3>| v.iter().map(|n| -*n).collect::<Vec<_>>();
        Surface {
            positions: self.positions.clone(),
            triangles: self.triangles.iter().map(|t| [t[0], t[2], t[1]]).collect(),
            loops: self.loops.iter().map(|l| l.iter().rev().copied().collect()).collect(),
            face_normals: neg(&self.face_normals),
            face_areas: self.face_areas.clone(),
            vertex_normals: neg(&self.vertex_normals),
            corner_normals: self.corner_normals.iter().map(|c| [-c[0], -c[2], -c[1]]).collect(),
            curvature: self.curvature.iter().map(|c| FaceCurvature { e: -c.e, f: -c.f, g: -c.g, ..*c }).collect(),
        }
    }

    /// Total area, mm².
    pub fn area(&self) -> f64 {
        self.face_areas.iter().sum()
    }
}

/// Topological and geometric figures of a mesh, as `slitpath info` prints them.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MeshReport {
    pub vertices: usize,
    pub faces: usize,
    pub edges: usize,
    pub components: usize,
    pub boundary_loops: usize,
    /// Vertex count of each boundary loop, outer loop first.
    pub loop_vertex_counts: Vec<usize>,
    pub euler_characteristic: i64,
    /// Total genus over all components.
    pub genus: i64,
    /// No boundary edge at all (a watertight solid).
    pub closed: bool,
    pub degenerate_faces_dropped: usize,
    pub duplicate_faces_dropped: usize,
    pub pinch_vertices_split: usize,
    /// Faces whose winding was flipped to make the orientation consistent.
    pub faces_reoriented: usize,
    /// Faces in components other than the one planned.
    pub faces_in_other_components: usize,
    pub area_mm2: f64,
    /// `[[min x, min y, min z], [max x, max y, max z]]`, millimetres.
    pub bbox: [[f64; 3]; 2],
    /// For a closed solid: the same figures for the extracted machinable top surface.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub machined: Option<Box<MeshReport>>,
    /// The loops the surface to plan was cut along, one per handle, when its genus is > 0
    /// ([`handles`]): the planned surface is a disk with holes (each cut adds one or two).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub handle_cuts: Vec<HandleCut>,
}

/// The result of the stage: the report of the whole model and the surface to plan.
#[derive(Clone, Debug)]
pub struct MeshOutput {
    pub report: MeshReport,
    pub surface: Surface,
}

/// Everything that can be wrong with an input model. Variants carry the index at fault.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MeshError {
    #[error("the STL file is empty")]
    Empty,
    #[error(
        "truncated binary STL: it declares {triangles} triangles ({expected_bytes} bytes) but has {actual_bytes} bytes"
    )]
    Truncated { triangles: u64, expected_bytes: u64, actual_bytes: u64 },
    #[error("not a valid STL: line {line}: {message}")]
    AsciiSyntax { line: usize, message: String },
    #[error("triangle {triangle} has a non-finite coordinate (NaN or infinity)")]
    NonFinite { triangle: usize },
    #[error("the model has {count} triangles, more than the limit of {cap}")]
    TooManyTriangles { count: u64, cap: usize },
    #[error("the STL has no triangles")]
    NoTriangles,
    #[error("all {dropped} triangles are degenerate (zero area): nothing is left to machine")]
    AllDegenerate { dropped: usize },
    #[error("non-manifold edge between vertices {a} {pa:?} and {b} {pb:?}: it is shared by {faces} faces (at most 2 allowed)")]
    NonManifoldEdge { a: u32, b: u32, pa: [f64; 3], pb: [f64; 3], faces: usize },
    #[error("the surface is not orientable (like a Möbius strip): the winding conflicts at the edge between vertices {a} and {b}")]
    NonOrientable { a: u32, b: u32 },
    #[error("no face of the closed solid faces the tool axis {axis:?} within the wall angle of {wall_angle_deg}°: pick another tool axis")]
    NothingFacesTool { axis: [f64; 3], wall_angle_deg: f64 },
    #[error("the surface to machine is closed (it has no boundary loop): it cannot be flattened")]
    Closed,
    #[error("the surface to machine has genus {genus} ({loops} boundary loops): its handles must be cut first (a disk with holes is planned)")]
    HighGenus { genus: i64, loops: usize },
    #[error("cutting the handles: {0}")]
    Handles(#[from] HandleError),
    #[error("invalid mesh option: {0}")]
    InvalidOption(String),
}

/// Reads STL bytes and returns the report and the surface to plan (one-off entry of the stage).
pub fn load(bytes: &[u8], options: &MeshOptions) -> Result<MeshOutput, MeshError> {
    load_with_progress(bytes, options, &mut |_, _, _| {})
}

/// The steps of [`load_with_progress`], in order.
pub const LOAD_STEPS: [&str; 2] = ["reading the STL", "checking the mesh"];

/// [`load`], calling `progress(step, done, total)` as each of [`LOAD_STEPS`] starts (the page
/// shows them: a big part takes a moment).
pub fn load_with_progress(
    bytes: &[u8],
    options: &MeshOptions,
    progress: &mut dyn FnMut(&str, usize, usize),
) -> Result<MeshOutput, MeshError> {
    check_options(options)?;
    progress(LOAD_STEPS[0], 0, LOAD_STEPS.len());
    let soup = stl::read(bytes, options.max_triangles)?;
    progress(LOAD_STEPS[1], 1, LOAD_STEPS.len());
    from_triangles(&soup, options)
}

/// How far a ball of radius `r` placed along the unit normal `n` at a point of a facet with unit
/// normal `facet` must move out along `n` to touch the facet's plane instead of dipping into it:
/// R(1/cos α − 1), α the angle between them (infinite when `n` does not face the same side).
/// With exact facets the toolpath moves it so (`toolpath::clear_facets`).
pub fn ball_lift_mm(n: DVec3, facet: DVec3, r: f64) -> f64 {
    let cos = n.dot(facet);
    if cos > 0.0 {
        r * (1.0 / cos - 1.0)
    } else {
        f64::INFINITY
    }
}

/// Same as [`load`] from a triangle soup or an indexed mesh (corners are welded again).
pub fn from_triangles(mesh: &TriMesh, options: &MeshOptions) -> Result<MeshOutput, MeshError> {
    check_options(options)?;
    let axis = options.tool_axis.normalize();
    let welded = weld::weld(mesh, options.weld_tolerance_rel)?;
    let topo = topology::analyse(&welded.mesh, axis)?;
    let mut report = topology::report(&topo);
    report.degenerate_faces_dropped = welded.degenerate_dropped;
    report.duplicate_faces_dropped = welded.duplicates_dropped;

    let (best, mut component) = topology::largest_component(&topo);
    report.faces_in_other_components = topo.mesh.triangles.len() - topo.components[best].faces;
    if topo.components[best].closed() {
        // A solid: machine what the tool sees (steep walls become holes).
        let top = extract::top_surface(&component.mesh, axis, options.wall_angle_deg)?;
        let top_topo = topology::analyse(&top, axis)?;
        let (top_best, top_component) = topology::largest_component(&top_topo);
        // The report describes the surface that is planned: the largest top component.
        let mut machined = topology::component_report(&top_topo, top_best);
        machined.faces_in_other_components = top.triangles.len() - top_component.mesh.triangles.len();
        report.machined = Some(Box::new(machined));
        component = top_component;
    }
    let surface = geometry::build_surface(component)?;
    let (surface, handle_cuts) = handles::cut_handles(surface, &options.handles)?;
    report.handle_cuts = handle_cuts;
    Ok(MeshOutput { report, surface })
}

fn check_options(options: &MeshOptions) -> Result<(), MeshError> {
    let o = options;
    if !(o.weld_tolerance_rel.is_finite() && o.weld_tolerance_rel >= 0.0 && o.weld_tolerance_rel < 0.1) {
        return Err(MeshError::InvalidOption(format!(
            "weld tolerance {} must be in [0, 0.1) of the bounding-box diagonal",
            o.weld_tolerance_rel
        )));
    }
    if !(o.tool_axis.is_finite() && o.tool_axis.length() > 1e-12) {
        return Err(MeshError::InvalidOption(format!("tool axis {:?} must be a non-zero vector", o.tool_axis)));
    }
    if !(o.wall_angle_deg > 0.0 && o.wall_angle_deg < 90.0) {
        return Err(MeshError::InvalidOption(format!(
            "wall angle {}° must be strictly between 0° and 90°",
            o.wall_angle_deg
        )));
    }
    Ok(())
}
