//! Stage 1 for CAD input — `step`: STEP bytes (AP203/AP214/AP242) → exact faces → a welded,
//! face-tagged triangle mesh → the planner's [`Surface`](crate::mesh::Surface).
//!
//! What it computes (issue 36 item 1; `docs/step.md` for the choice of a reader of our own over
//! the crates):
//! 1. [`parse`]: the DATA section of an ISO 10303-21 file into an instance table.
//! 2. [`model`]: faces with their exact surfaces (planes, cylinders, cones, spheres, tori,
//!    rational and polynomial B-splines), bounds and edges, in millimetres (length units read).
//! 3. [`tessellate`]: edges sampled once and shared by the faces on both sides (so adjacent faces
//!    give one manifold mesh), every face meshed in its parameter domain with its holes until each
//!    facet is within the chordal tolerance of the surface; each triangle tagged with its face.
//! 4. [`load`]: the selected faces' mesh through [`mesh::from_triangles`] (the STL path from
//!    there on), refused unless it is one open surface.
//!
//! Preconditions: faces are ADVANCED_FACEs; a face on a periodic surface has a seam edge where
//! its loop goes round (as OpenCascade writes it), or is a band bounded by two loops that go
//! round once in opposite senses (as Parasolid writes it). Invariants of the output: triangles of a face
//! are wound with the face's normal; vertices on a shared edge are the same vertex in both faces.
//! Bad input never panics: every fault is a [`StepError`] naming the `#id` at fault.

pub mod geom;
pub mod model;
pub mod nurbs;
pub mod parse;
pub mod tessellate;
pub mod triangulate;

use crate::mesh::{self, MeshOptions, MeshOutput, TriMesh};
use serde::Serialize;

pub use model::Model;
pub use tessellate::Tessellation;

/// Options of the STEP stage. `Default` gives the documented defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct StepOptions {
    /// Largest distance between a facet (or an edge's chord) and the exact surface, mm.
    /// Default 0.01 mm: half the planner's default scallop limit of 0.02 mm.
    pub chordal_tol_mm: f64,
    /// Longest facet edge, mm; `None` = 1/50 of the model's bounding-box diagonal (the slit map
    /// needs vertices inside flat faces too). Default `None`.
    pub max_edge_mm: Option<f64>,
    /// Faces to tessellate, by STEP id; `None` = all. Default `None`.
    pub faces: Option<Vec<u64>>,
    /// Refused above this many triangles. Default 2 000 000.
    pub max_triangles: usize,
}

impl Default for StepOptions {
    fn default() -> Self {
        Self { chordal_tol_mm: 0.01, max_edge_mm: None, faces: None, max_triangles: 2_000_000 }
    }
}

/// Everything that can be wrong with a STEP input. Variants carry the `#id` (or line) at fault.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StepError {
    #[error("not a STEP file (it does not start with ISO-10303-21;)")]
    NotStep,
    #[error("truncated STEP file at line {line}{}: {message}", at(*id))]
    Truncated { id: Option<u64>, line: usize, message: String },
    #[error("STEP syntax error at line {line}{}: {message}", at(*id))]
    Syntax { id: Option<u64>, line: usize, message: String },
    #[error("#{id}: {message}")]
    Entity { id: u64, message: String },
    #[error("#{id}: {entity} is not supported")]
    Unsupported { id: u64, entity: String },
    #[error("the STEP file has no ADVANCED_FACE")]
    NoFaces,
    #[error("there is no face #{id}; the faces are {}", list(faces))]
    UnknownFace { id: u64, faces: Vec<u64> },
    #[error("face #{face} cannot be tessellated: {message}")]
    Tessellation { face: u64, message: String },
    #[error("tessellating up to face #{face} gives more than {cap} triangles: raise the chordal tolerance")]
    TooManyTriangles { face: u64, cap: usize },
    #[error(
        "the faces {} do not form one open surface ({reason}); choose faces with --faces (see `slitpath faces`)",
        list(faces)
    )]
    NotOneSurface { faces: Vec<u64>, reason: String },
    #[error("invalid STEP option: {0}")]
    InvalidOption(String),
    #[error("{0}")]
    Mesh(#[from] mesh::MeshError),
}

fn at(id: Option<u64>) -> String {
    id.map_or(String::new(), |i| format!(" (instance #{i})"))
}

fn list(ids: &[u64]) -> String {
    ids.iter().map(|i| format!("#{i}")).collect::<Vec<_>>().join(", ")
}

/// One face as the report lists it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FaceInfo {
    /// The ADVANCED_FACE's id.
    pub id: u64,
    /// `plane`, `cylinder`, `cone`, `sphere`, `torus`, `b-spline` or `rational b-spline`.
    pub surface: String,
    pub surface_id: u64,
    /// Number of edge loops (1 + holes).
    pub loops: usize,
    /// Area of its facets, mm².
    pub area_mm2: f64,
    pub triangles: usize,
    /// The largest facet-to-surface distance measured on it, mm.
    pub chordal_error_mm: f64,
    /// Edge uses of its loops whose parameters came from a PCURVE (the others were projected).
    pub pcurve_edges: usize,
    /// Edge uses whose pcurves on its surface lay off the edge (farther than a tenth of the
    /// chordal tolerance from its samples): projected instead.
    pub pcurves_off_surface: usize,
    /// Faces sharing an edge with it (all faces of the file, selected or not).
    pub adjacent: Vec<u64>,
}

/// The `step` section of the reports.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StepReport {
    /// All faces of the file, in id order.
    pub faces_in_file: Vec<u64>,
    /// The faces tessellated (and planned), with their figures.
    pub faces: Vec<FaceInfo>,
    /// Whether `faces` were chosen by [`load`] as the top of a closed solid (no selection given).
    pub top_of_solid: bool,
    /// Millimetres per file unit, and the unit's name.
    pub unit_mm: f64,
    pub unit: String,
    pub chordal_tol_mm: f64,
    /// The largest facet-to-surface distance measured over the tessellation, mm.
    pub chordal_error_mm: f64,
    pub triangles: usize,
    pub read_ms: f64,
    pub tessellate_ms: f64,
}

/// The result of [`load`]: the planner's input and the STEP report.
#[derive(Clone, Debug)]
pub struct StepOutput {
    pub mesh: MeshOutput,
    pub step: StepReport,
    /// The STEP face of each triangle of `mesh.surface` (the mesh stage keeps the triangle order
    /// of one open component, checked by [`load`]).
    pub face_of_triangle: Vec<u64>,
}

/// Whether `bytes` look like a STEP file (the ISO 10303-21 magic after any leading blanks).
pub fn is_step(bytes: &[u8]) -> bool {
    let start = bytes.iter().position(|c| !c.is_ascii_whitespace()).unwrap_or(bytes.len());
    bytes[start..].len() >= 12 && bytes[start..start + 12].eq_ignore_ascii_case(b"ISO-10303-21")
}

/// Reads the B-rep of a STEP file.
pub fn read(bytes: &[u8]) -> Result<Model, StepError> {
    model::decode(&parse::parse(bytes)?)
}

fn check_options(o: &StepOptions) -> Result<(), StepError> {
    if !(o.chordal_tol_mm.is_finite() && o.chordal_tol_mm > 0.0) {
        return Err(StepError::InvalidOption(format!("chordal tolerance {} mm must be positive", o.chordal_tol_mm)));
    }
    if let Some(e) = o.max_edge_mm {
        if !(e.is_finite() && e > 0.0) {
            return Err(StepError::InvalidOption(format!("maximum edge {e} mm must be positive")));
        }
    }
    Ok(())
}

/// Reads and tessellates (no mesh checks): what `slitpath faces` shows.
pub fn read_and_tessellate(
    bytes: &[u8],
    o: &StepOptions,
    now: &dyn Fn() -> f64,
) -> Result<(Model, Tessellation, [f64; 2]), StepError> {
    check_options(o)?;
    let t0 = now();
    let model = read(bytes)?;
    let read_ms = now() - t0;
    let (tess, tessellate_ms) = tessellate_model(&model, o, now)?;
    Ok((model, tess, [read_ms, tessellate_ms]))
}

/// The tessellation half of [`read_and_tessellate`], of a model already read (so a caller can
/// report progress between the two), with its time in milliseconds.
pub fn tessellate_model(
    model: &Model,
    o: &StepOptions,
    now: &dyn Fn() -> f64,
) -> Result<(Tessellation, f64), StepError> {
    check_options(o)?;
    let t1 = now();
    let tess = tessellate::tessellate(model, o.faces.as_deref(), o)?;
    Ok((tess, now() - t1))
}

/// STEP bytes → the planner's surface and the STEP report. `now` gives milliseconds.
///
/// Without a face selection, a file whose faces enclose a solid is planned on its top, as an STL
/// solid is ([`mesh::extract`]), but by whole faces: those whose every facet faces the tool axis
/// within the wall angle ([`MeshOptions`]), the largest set of them connected by shared edges
/// ([`StepReport::top_of_solid`]). Whole faces keep the exact boundaries of the CAD model (a
/// fillet down to a wall is left out rather than cut along a tessellation's zigzag).
pub fn load(
    bytes: &[u8],
    o: &StepOptions,
    mesh_options: &MeshOptions,
    now: &dyn Fn() -> f64,
) -> Result<StepOutput, StepError> {
    let (model, tess, times) = read_and_tessellate(bytes, o, now)?;
    load_tessellated(&model, tess, o, mesh_options, times)
}

/// [`load`] of a file already read and tessellated: `all` holds at least the faces `o.faces`
/// (all the file's when `None`), `times` the read and tessellation milliseconds to report. A page
/// that lists a file's faces and then plans on a selection tessellates it once.
pub fn load_from(
    model: &Model,
    all: &Tessellation,
    o: &StepOptions,
    mesh_options: &MeshOptions,
    times: [f64; 2],
) -> Result<StepOutput, StepError> {
    check_options(o)?;
    let tess = match &o.faces {
        Some(ids) => all.subset(ids)?,
        None => all.clone(),
    };
    load_tessellated(model, tess, o, mesh_options, times)
}

/// [`load`] after the tessellation `tess` of the faces `o.faces` (all when `None`).
fn load_tessellated(
    model: &Model,
    tess: Tessellation,
    o: &StepOptions,
    mesh_options: &MeshOptions,
    times: [f64; 2],
) -> Result<StepOutput, StepError> {
    let meshed = |tess: &Tessellation| {
        let trimesh = TriMesh { positions: tess.positions.clone(), triangles: tess.triangles.clone() };
        mesh::from_triangles(&trimesh, mesh_options)
    };
    let out = meshed(&tess)?;
    if o.faces.is_none() && out.report.closed {
        let top = top_faces(&tess, mesh_options)?;
        let tess = tess.subset(&top)?;
        let out = meshed(&tess)?;
        let o = StepOptions { faces: Some(top), ..o.clone() };
        let mut loaded = one_surface(model, tess, out, &o, times)?;
        loaded.step.top_of_solid = true;
        return Ok(loaded);
    }
    one_surface(model, tess, out, o, times)
}

/// The output of `tess` meshed as `out`, checked to be one open surface of all its facets.
fn one_surface(
    model: &Model,
    tess: Tessellation,
    out: MeshOutput,
    o: &StepOptions,
    [read_ms, tessellate_ms]: [f64; 2],
) -> Result<StepOutput, StepError> {
    let selected: Vec<u64> = tess.faces.iter().map(|f| f.id).collect();
    let r = &out.report;
    let reason = if r.closed {
        Some("they enclose a solid".to_string())
    } else if r.components > 1 {
        Some(format!("{} separate pieces", r.components))
    } else if out.surface.triangles.len() != tess.triangles.len() {
        Some(format!("{} degenerate and {} duplicate facets", r.degenerate_faces_dropped, r.duplicate_faces_dropped))
    } else {
        None
    };
    if let Some(reason) = reason {
        return Err(StepError::NotOneSurface { faces: selected, reason });
    }
    let step = StepReport {
        faces_in_file: model.faces.iter().map(|f| f.id).collect(),
        faces: tess.faces,
        top_of_solid: false,
        unit_mm: model.unit_mm,
        unit: model.unit_name.clone(),
        chordal_tol_mm: o.chordal_tol_mm,
        chordal_error_mm: tess.chordal_error_mm,
        triangles: tess.triangles.len(),
        read_ms,
        tessellate_ms,
    };
    Ok(StepOutput { mesh: out, step, face_of_triangle: tess.face_of_triangle })
}

/// The faces of a closed tessellation that face the tool: every facet's outward normal within
/// the wall angle of the axis; of those, the largest set (by area) connected through shared
/// edges, in id order.
fn top_faces(tess: &Tessellation, mesh_options: &MeshOptions) -> Result<Vec<u64>, StepError> {
    let axis = mesh_options.tool_axis.normalize();
    let cos_wall = crate::num::cos(mesh_options.wall_angle_deg.to_radians());
    let corners = |t: &[u32; 3]| t.map(|v| tess.positions[v as usize]);
    // Outward: the facets' signed volume is positive (a solid written inside out is turned).
    let volume: f64 = tess
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = corners(t);
            a.dot(b.cross(c))
        })
        .sum();
    let outward = if volume < 0.0 { -1.0 } else { 1.0 };
    let mut faces_tool = std::collections::BTreeMap::new();
    for (t, &face) in tess.triangles.iter().zip(&tess.face_of_triangle) {
        let [a, b, c] = corners(t);
        let n = outward * (b - a).cross(c - a).normalize_or_zero();
        let ok = faces_tool.entry(face).or_insert(true);
        *ok &= n.dot(axis) >= cos_wall;
    }
    let facing: Vec<&FaceInfo> = tess.faces.iter().filter(|f| faces_tool.get(&f.id) == Some(&true)).collect();
    if facing.is_empty() {
        return Err(StepError::Mesh(mesh::MeshError::NothingFacesTool {
            axis: axis.to_array(),
            wall_angle_deg: mesh_options.wall_angle_deg,
        }));
    }
    let index: std::collections::BTreeMap<u64, usize> = facing.iter().enumerate().map(|(i, f)| (f.id, i)).collect();
    // Connected sets by shared edges, the largest by area (the first in id order on a tie).
    let mut set = vec![usize::MAX; facing.len()];
    let mut best: (f64, usize) = (-1.0, 0);
    for start in 0..facing.len() {
        if set[start] != usize::MAX {
            continue;
        }
        let (mut stack, mut area) = (vec![start], 0.0);
        set[start] = start;
        while let Some(i) = stack.pop() {
            area += facing[i].area_mm2;
            for n in &facing[i].adjacent {
                if let Some(&j) = index.get(n) {
                    if set[j] == usize::MAX {
                        set[j] = start;
                        stack.push(j);
                    }
                }
            }
        }
        if area > best.0 {
            best = (area, start);
        }
    }
    Ok(facing.iter().zip(&set).filter(|(_, &s)| s == best.1).map(|(f, _)| f.id).collect())
}
