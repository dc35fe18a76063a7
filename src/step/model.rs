//! Instance table → typed B-rep: faces with their exact surfaces and bounds, edges with their
//! 3D curves and end vertices, in millimetres.
//!
//! Read: ADVANCED_FACE (and FACE_SURFACE) with FACE_OUTER_BOUND / FACE_BOUND of EDGE_LOOPs
//! (a VERTEX_LOOP, a sphere's pole or a cone's apex, is kept as a point the tessellator closes
//! the face at); ORIENTED_EDGE, EDGE_CURVE,
//! VERTEX_POINT; surfaces PLANE, CYLINDRICAL_, CONICAL_, SPHERICAL_, TOROIDAL_SURFACE and
//! B_SPLINE_SURFACE_WITH_KNOTS (simple or complex, RATIONAL_B_SPLINE_SURFACE too); curves LINE,
//! CIRCLE, ELLIPSE, B_SPLINE_CURVE_WITH_KNOTS (rational too), SURFACE_CURVE / SEAM_CURVE (their 3D
//! curve, and the PCURVEs among their associated geometry: a 2D LINE, CIRCLE, ELLIPSE or
//! B_SPLINE_CURVE_WITH_KNOTS in a DEFINITIONAL_REPRESENTATION, on a surface of a kind read here).
//! A PCURVE this reader cannot use (another curve type, a malformed instance) is left out, never
//! an error: the tessellator then projects the edge's 3D samples onto the surface, as it does
//! for edges without one.
//! Pcurve units: its coordinates are the surface's parameters as the file writes them, so the
//! length unit scales them on a plane (both), a cylinder or cone (`v`), and the plane-angle unit
//! the angles (`u` of the elementary surfaces, `v` of a sphere or torus); a B-spline surface's
//! parameters are its knots' and are not scaled. A pcurve's own parameter is read as the file
//! writes it (a LINE's VECTOR magnitude kept, a CIRCLE's angle in the plane-angle unit).
//! Units: the LENGTH_UNIT the representation context assigns (SI with prefix, or CONVERSION_BASED_UNIT such as INCH) and the
//! PLANE_ANGLE_UNIT (radian or degree); without one, millimetres and radians.
//! Assembly placements (MAPPED_ITEM, ITEM_DEFINED_TRANSFORMATION) are not applied: every face is
//! read in the coordinates it is written in.

use super::geom::{Curve, Frame, Surface};
use super::nurbs;
use super::parse::{Entity, Param, Record, Table};
use super::StepError;
use glam::{DVec2, DVec3};
use std::collections::BTreeMap;
use std::f64::consts::TAU;

/// A face bound: its edges in loop order, each with `true` when used in the edge's direction.
#[derive(Clone, Debug)]
pub struct Bound {
    pub id: u64,
    pub outer: bool,
    pub edges: Vec<(u64, bool)>,
}

#[derive(Clone, Debug)]
pub struct Face {
    pub id: u64,
    pub surface_id: u64,
    pub surface: Surface,
    /// The face normal is the surface's (`true`) or its opposite.
    pub same_sense: bool,
    pub bounds: Vec<Bound>,
    /// Points bounding the face alone (VERTEX_LOOPs: a sphere's pole, a cone's apex), mm.
    pub vertex_loops: Vec<DVec3>,
}

#[derive(Clone, Debug)]
pub struct Edge {
    pub id: u64,
    pub start: u64,
    pub end: u64,
    pub curve: Curve,
    /// The edge runs along the curve's direction.
    pub same_sense: bool,
    /// `curve`'s parameter per parameter of the curve as the file writes it (a LINE's is
    /// normalised to millimetres, a CIRCLE's angle to radians; 1 for B-splines): the file's
    /// parameter of `curve.point(t)` is `t / param_scale`, the one its pcurves share.
    pub param_scale: f64,
    /// The PCURVEs of a SURFACE_CURVE or SEAM_CURVE (a seam has two on one surface).
    pub pcurves: Vec<Pcurve>,
}

/// An edge's curve in the parameters of one surface (PCURVE).
#[derive(Clone, Debug)]
pub struct Pcurve {
    /// The PCURVE's id.
    pub id: u64,
    /// The id of its basis surface (compared with a face's `surface_id`).
    pub surface_id: u64,
    /// The 2D curve, z = 0, in the file's units (unscaled).
    pub curve: Curve,
    /// `curve`'s parameter per file parameter (a CIRCLE's: radians per plane-angle unit).
    pub param_scale: f64,
    /// The surface's parameters per file coordinate of the curve (see the module docs).
    pub scale: DVec2,
    /// The file-parameter range of a bounded curve (a B-spline's knots, a full turn of a
    /// circle or ellipse); `None` for a line.
    pub range: Option<(f64, f64)>,
}

impl Pcurve {
    /// The surface parameters at the file parameter `t`.
    pub fn uv(&self, t: f64) -> DVec2 {
        let q = self.curve.point(t * self.param_scale);
        DVec2::new(q.x, q.y) * self.scale
    }

    /// The derivative of [`Pcurve::uv`] with respect to `t`.
    pub fn duv(&self, t: f64) -> DVec2 {
        let d = self.curve.derivative(t * self.param_scale) * self.param_scale;
        DVec2::new(d.x, d.y) * self.scale
    }
}

/// The B-rep of a STEP file.
#[derive(Clone, Debug)]
pub struct Model {
    pub faces: Vec<Face>,
    pub edges: BTreeMap<u64, Edge>,
    pub vertices: BTreeMap<u64, DVec3>,
    /// Millimetres per file length unit.
    pub unit_mm: f64,
    /// The unit as written (`millimetre`, `INCH`, …; `assumed millimetre` when none is given).
    pub unit_name: String,
}

/// A pcurve's 2D curve, its parameter scale and its file-parameter range (see [`Pcurve`]).
type Curve2d = (Curve, f64, Option<(f64, f64)>);

struct Reader<'a> {
    table: &'a Table,
    mm: f64,
    rad: f64,
}

fn bad(id: u64, message: impl Into<String>) -> StepError {
    StepError::Entity { id, message: message.into() }
}

/// Decodes every face of the table.
pub fn decode(table: &Table) -> Result<Model, StepError> {
    let (unit_mm, unit_name) = length_unit(table)?;
    let rad = angle_unit(table)?;
    let r = Reader { table, mm: unit_mm, rad };
    let mut faces = Vec::new();
    let mut edges = BTreeMap::new();
    let mut vertices = BTreeMap::new();
    for (&id, e) in table {
        let Some(rec) = e.record("ADVANCED_FACE").or_else(|| e.record("FACE_SURFACE")) else { continue };
        faces.push(r.face(id, rec, &mut edges, &mut vertices)?);
    }
    if faces.is_empty() {
        return Err(StepError::NoFaces);
    }
    Ok(Model { faces, edges, vertices, unit_mm, unit_name })
}

impl Reader<'_> {
    fn get(&self, from: u64, id: u64) -> Result<&Entity, StepError> {
        self.table.get(&id).ok_or_else(|| bad(from, format!("refers to #{id}, which is not defined")))
    }

    fn face(
        &self,
        id: u64,
        rec: &Record,
        edges: &mut BTreeMap<u64, Edge>,
        vertices: &mut BTreeMap<u64, DVec3>,
    ) -> Result<Face, StepError> {
        let p = Params::new(id, rec, 4)?;
        let surface_id = p.reference(2)?;
        let surface = self.surface(surface_id)?;
        let same_sense = p.boolean(3)?;
        let mut bounds = Vec::new();
        let mut vertex_loops = Vec::new();
        for b in p.refs(1)? {
            let e = self.get(id, b)?;
            let outer = e.record("FACE_OUTER_BOUND").is_some();
            let Some(rec) = e.record("FACE_OUTER_BOUND").or_else(|| e.record("FACE_BOUND")) else {
                return Err(bad(b, format!("{} is not a face bound", e.name())));
            };
            let loop_id = Params::new(b, rec, 3)?.reference(1)?;
            let l = self.get(b, loop_id)?;
            if let Some(vl) = l.record("VERTEX_LOOP") {
                let v = Params::new(loop_id, vl, 2)?.reference(1)?;
                let ve = self.get(loop_id, v)?;
                let vr = ve.record("VERTEX_POINT").ok_or_else(|| bad(v, "not a VERTEX_POINT"))?;
                vertex_loops.push(self.point(Params::new(v, vr, 2)?.reference(1)?)?);
                continue;
            }
            let Some(lrec) = l.record("EDGE_LOOP") else {
                return Err(bad(loop_id, format!("{} is not an edge loop", l.name())));
            };
            let mut list = Vec::new();
            for oe in Params::new(loop_id, lrec, 2)?.refs(1)? {
                let o = self.get(loop_id, oe)?;
                let orec = o.record("ORIENTED_EDGE").ok_or_else(|| bad(oe, "not an ORIENTED_EDGE"))?;
                let op = Params::new(oe, orec, 5)?;
                let edge_id = op.reference(3)?;
                let forward = op.boolean(4)?;
                if let std::collections::btree_map::Entry::Vacant(slot) = edges.entry(edge_id) {
                    slot.insert(self.edge(edge_id, vertices)?);
                }
                list.push((edge_id, forward));
            }
            if list.is_empty() {
                return Err(bad(loop_id, "an edge loop without edges"));
            }
            bounds.push(Bound { id: loop_id, outer, edges: list });
        }
        if bounds.is_empty() {
            return Err(bad(id, "the face has no edge loop"));
        }
        Ok(Face { id, surface_id, surface, same_sense, bounds, vertex_loops })
    }

    fn edge(&self, id: u64, vertices: &mut BTreeMap<u64, DVec3>) -> Result<Edge, StepError> {
        let e = self.get(id, id)?;
        let rec = e.record("EDGE_CURVE").ok_or_else(|| bad(id, format!("{} is not an EDGE_CURVE", e.name())))?;
        let p = Params::new(id, rec, 5)?;
        let (start, end) = (p.reference(1)?, p.reference(2)?);
        for v in [start, end] {
            if let std::collections::btree_map::Entry::Vacant(slot) = vertices.entry(v) {
                let ve = self.get(id, v)?;
                let vr = ve.record("VERTEX_POINT").ok_or_else(|| bad(v, "not a VERTEX_POINT"))?;
                slot.insert(self.point(Params::new(v, vr, 2)?.reference(1)?)?);
            }
        }
        let curve_id = p.reference(3)?;
        let curve = self.curve(curve_id)?;
        let param_scale = self.param_scale(curve_id, &curve);
        let pcurves = self.pcurves(curve_id);
        Ok(Edge { id, start, end, curve, same_sense: p.boolean(4)?, param_scale, pcurves })
    }

    /// See [`Edge::param_scale`]: the curve `id` (read as `curve`) has parameter `t` where the
    /// file's has `t / param_scale`.
    fn param_scale(&self, id: u64, curve: &Curve) -> f64 {
        match curve {
            Curve::BSpline(_) => 1.0,
            Curve::Circle(..) | Curve::Ellipse(..) => self.rad,
            Curve::Line { .. } => {
                // Follow SURFACE_CURVEs down to the LINE; its VECTOR's magnitude, in file units.
                let mut at = id;
                for _ in 0..4 {
                    let Some(e) = self.table.get(&at) else { break };
                    let rec = &e.records[0];
                    match rec.name.as_str() {
                        "SURFACE_CURVE" | "SEAM_CURVE" => match rec.params.get(1) {
                            Some(Param::Ref(r)) => at = *r,
                            _ => break,
                        },
                        "LINE" => {
                            let magnitude = match rec.params.get(2) {
                                Some(Param::Ref(v)) => self
                                    .table
                                    .get(v)
                                    .and_then(|v| v.record("VECTOR"))
                                    .and_then(|v| v.params.get(2))
                                    .and_then(as_real),
                                _ => None,
                            };
                            return magnitude.filter(|m| m.is_finite() && *m > 0.0).map_or(self.mm, |m| m * self.mm);
                        }
                        _ => break,
                    }
                }
                self.mm
            }
        }
    }

    /// The usable PCURVEs of a SURFACE_CURVE or SEAM_CURVE `id` (none for another curve): those
    /// whose 2D curve and basis surface this reader knows. Faults leave a pcurve out.
    fn pcurves(&self, id: u64) -> Vec<Pcurve> {
        let Some(e) = self.table.get(&id) else { return Vec::new() };
        let Some(rec) = e.record("SURFACE_CURVE").or_else(|| e.record("SEAM_CURVE")) else { return Vec::new() };
        let Some(Param::List(items)) = rec.params.get(2) else { return Vec::new() };
        items
            .iter()
            .filter_map(|item| match item {
                Param::Ref(r) => self.pcurve(*r),
                _ => None,
            })
            .collect()
    }

    fn pcurve(&self, id: u64) -> Option<Pcurve> {
        let rec = self.table.get(&id)?.record("PCURVE")?;
        let p = Params::new(id, rec, 3).ok()?;
        let surface_id = p.reference(1).ok()?;
        let surface = self.table.get(&surface_id)?;
        let (mm, rad) = (self.mm, self.rad);
        let scale = if surface.record("B_SPLINE_SURFACE_WITH_KNOTS").is_some() {
            DVec2::ONE
        } else {
            match surface.records[0].name.as_str() {
                "PLANE" => DVec2::new(mm, mm),
                "CYLINDRICAL_SURFACE" | "CONICAL_SURFACE" => DVec2::new(rad, mm),
                "SPHERICAL_SURFACE" | "TOROIDAL_SURFACE" => DVec2::new(rad, rad),
                _ => return None,
            }
        };
        let rep = p.reference(2).ok()?;
        let rrec = self.table.get(&rep)?.record("DEFINITIONAL_REPRESENTATION")?;
        let items = Params::new(rep, rrec, 2).ok()?.refs(1).ok()?;
        let &[curve_id] = items.as_slice() else { return None };
        // The 2D curve in the file's own units: a reader that scales nothing.
        let plain = Reader { table: self.table, mm: 1.0, rad: 1.0 };
        let (curve, param_scale, range) = plain.curve_2d(curve_id, self.rad)?;
        Some(Pcurve { id, surface_id, curve, param_scale, scale, range })
    }

    /// A 2D curve (z = 0) as written, its parameter scale and file-parameter range (see
    /// [`Pcurve`]); `rad` is the file's radians per plane-angle unit.
    fn curve_2d(&self, id: u64, rad: f64) -> Option<Curve2d> {
        let e = self.table.get(&id)?;
        let point2 = |id: u64| -> Option<DVec3> {
            let rec = self.table.get(&id)?.record("CARTESIAN_POINT")?;
            match Params::new(id, rec, 2).ok()?.reals(1).ok()?.as_slice() {
                [x, y] => Some(DVec3::new(*x, *y, 0.0)),
                _ => None,
            }
        };
        let direction2 = |id: u64| -> Option<DVec3> {
            let rec = self.table.get(&id)?.record("DIRECTION")?;
            match Params::new(id, rec, 2).ok()?.reals(1).ok()?.as_slice() {
                [x, y] => DVec3::new(*x, *y, 0.0).try_normalize(),
                _ => None,
            }
        };
        let placement2 = |id: u64| -> Option<Frame> {
            let rec = self.table.get(&id)?.record("AXIS2_PLACEMENT_2D")?;
            let p = Params::new(id, rec, 2).ok()?;
            let origin = point2(p.reference(1).ok()?)?;
            let x = if p.is_null(2) { DVec3::X } else { direction2(p.reference(2).ok()?)? };
            Frame::new(origin, DVec3::Z, x)
        };
        if e.record("B_SPLINE_CURVE_WITH_KNOTS").is_some() {
            let curve = self.curve(id).ok()?;
            let Curve::BSpline(c) = &curve else { return None };
            if c.poles.iter().any(|p| p.z != 0.0) {
                return None;
            }
            let range = c.range();
            return Some((curve, 1.0, Some(range)));
        }
        let rec = &e.records[0];
        let p = Params::new(id, rec, 3).ok()?;
        let turn = Some((0.0, TAU / rad));
        match rec.name.as_str() {
            "LINE" => {
                let origin = point2(p.reference(1).ok()?)?;
                let v = p.reference(2).ok()?;
                let vp = Params::new(v, self.table.get(&v)?.record("VECTOR")?, 3).ok()?;
                let magnitude = vp.real(2).ok().filter(|m| m.is_finite() && *m > 0.0)?;
                Some((Curve::Line { origin, dir: direction2(vp.reference(1).ok()?)? * magnitude }, 1.0, None))
            }
            "CIRCLE" => {
                let r = p.real(2).ok().filter(|r| r.is_finite() && *r > 0.0)?;
                Some((Curve::Circle(placement2(p.reference(1).ok()?)?, r), rad, turn))
            }
            "ELLIPSE" => {
                let p = p.at_least(4).ok()?;
                let (a, b) = (p.real(2).ok()?, p.real(3).ok()?);
                if !(a.is_finite() && b.is_finite() && a > 0.0 && b > 0.0) {
                    return None;
                }
                Some((Curve::Ellipse(placement2(p.reference(1).ok()?)?, a, b), rad, turn))
            }
            _ => None,
        }
    }

    fn point(&self, id: u64) -> Result<DVec3, StepError> {
        let e = self.get(id, id)?;
        let rec =
            e.record("CARTESIAN_POINT").ok_or_else(|| bad(id, format!("{} is not a CARTESIAN_POINT", e.name())))?;
        let c = Params::new(id, rec, 2)?.reals(1)?;
        match c.as_slice() {
            [x, y, z] => Ok(DVec3::new(*x, *y, *z) * self.mm),
            [x, y] => Ok(DVec3::new(*x, *y, 0.0) * self.mm),
            _ => Err(bad(id, format!("a point with {} coordinates", c.len()))),
        }
    }

    fn direction(&self, id: u64) -> Result<DVec3, StepError> {
        let e = self.get(id, id)?;
        let rec = e.record("DIRECTION").ok_or_else(|| bad(id, format!("{} is not a DIRECTION", e.name())))?;
        let c = Params::new(id, rec, 2)?.reals(1)?;
        match c.as_slice() {
            [x, y, z] => Ok(DVec3::new(*x, *y, *z)),
            _ => Err(bad(id, "a direction without three ratios")),
        }
    }

    fn frame(&self, id: u64) -> Result<Frame, StepError> {
        let e = self.get(id, id)?;
        let rec = e
            .record("AXIS2_PLACEMENT_3D")
            .ok_or_else(|| bad(id, format!("{} is not an AXIS2_PLACEMENT_3D", e.name())))?;
        let p = Params::new(id, rec, 4)?;
        let origin = self.point(p.reference(1)?)?;
        let axis = if p.is_null(2) { DVec3::Z } else { self.direction(p.reference(2)?)? };
        let reference = if p.is_null(3) { DVec3::X } else { self.direction(p.reference(3)?)? };
        Frame::new(origin, axis, reference).ok_or_else(|| bad(id, "a zero axis"))
    }

    fn length(&self, p: &Params, k: usize) -> Result<f64, StepError> {
        let v = p.real(k)? * self.mm;
        if v.is_finite() && v >= 0.0 {
            Ok(v)
        } else {
            Err(bad(p.id, format!("parameter {} must be a non-negative length", k + 1)))
        }
    }

    fn surface(&self, id: u64) -> Result<Surface, StepError> {
        let e = self.get(id, id)?;
        if e.record("B_SPLINE_SURFACE_WITH_KNOTS").is_some() {
            return self.bspline_surface(id, e).map(|s| Surface::BSpline(Box::new(s)));
        }
        let rec = &e.records[0];
        let p = Params::new(id, rec, 2)?;
        let surface = match rec.name.as_str() {
            "PLANE" => Surface::Plane(self.frame(p.reference(1)?)?),
            "CYLINDRICAL_SURFACE" => Surface::Cylinder(self.frame(p.reference(1)?)?, self.length(&p.at_least(3)?, 2)?),
            "CONICAL_SURFACE" => {
                let p = p.at_least(4)?;
                Surface::Cone(self.frame(p.reference(1)?)?, self.length(&p, 2)?, p.real(3)? * self.rad)
            }
            "SPHERICAL_SURFACE" => Surface::Sphere(self.frame(p.reference(1)?)?, self.length(&p.at_least(3)?, 2)?),
            "TOROIDAL_SURFACE" => {
                let p = p.at_least(4)?;
                Surface::Torus(self.frame(p.reference(1)?)?, self.length(&p, 2)?, self.length(&p, 3)?)
            }
            other => return Err(StepError::Unsupported { id, entity: other.to_string() }),
        };
        Ok(surface)
    }

    fn bspline_surface(&self, id: u64, e: &Entity) -> Result<nurbs::Surface, StepError> {
        // A simple instance holds everything after its name; a complex one splits it.
        let (head, knots_rec) = match e.record("B_SPLINE_SURFACE") {
            Some(h) => {
                (Params::new(id, h, 7)?, Params::new(id, e.record("B_SPLINE_SURFACE_WITH_KNOTS").unwrap_or(h), 4)?)
            }
            None => {
                let r = Params::new(id, e.record("B_SPLINE_SURFACE_WITH_KNOTS").unwrap_or(&e.records[0]), 12)?;
                (r.shifted(1), r.shifted(8))
            }
        };
        let degree = [head.uint(0)?, head.uint(1)?];
        let rows = head.list(2)?;
        let mut poles = Vec::new();
        let nu = rows.len();
        let mut nv = 0;
        for row in rows {
            let Param::List(row) = row else { return Err(bad(id, "control points are not a list of lists")) };
            if nv == 0 {
                nv = row.len();
            } else if row.len() != nv {
                return Err(bad(id, "control point rows of different lengths"));
            }
            for q in row {
                let Param::Ref(q) = q else { return Err(bad(id, "a control point is not a reference")) };
                poles.push(self.point(*q)?);
            }
        }
        let knots = |k: usize, d: usize, n: usize| -> Result<Vec<f64>, StepError> {
            let mults: Vec<i64> = knots_rec.ints(k)?;
            nurbs::expand_knots(&mults, &knots_rec.reals(k + 2)?, d, n).map_err(|m| bad(id, m))
        };
        let knots = [knots(0, degree[0], nu)?, knots(1, degree[1], nv)?];
        let mut w = Vec::new();
        if let Some(rr) = e.record("RATIONAL_B_SPLINE_SURFACE") {
            for row in Params::new(id, rr, 1)?.list(0)? {
                let Param::List(row) = row else { return Err(bad(id, "weights are not a list of lists")) };
                for x in row {
                    w.push(as_real(x).ok_or_else(|| bad(id, "a weight is not a number"))?);
                }
            }
            if w.len() != poles.len() || w.iter().any(|x| x.is_nan() || *x <= 0.0) {
                return Err(bad(id, "weights must be positive, one per control point"));
            }
        }
        Ok(nurbs::Surface { degree, counts: [nu, nv], poles, weights: w, knots })
    }

    fn curve(&self, id: u64) -> Result<Curve, StepError> {
        let e = self.get(id, id)?;
        if e.record("B_SPLINE_CURVE_WITH_KNOTS").is_some() {
            let (head, kr) = match e.record("B_SPLINE_CURVE") {
                Some(h) => {
                    (Params::new(id, h, 5)?, Params::new(id, e.record("B_SPLINE_CURVE_WITH_KNOTS").unwrap_or(h), 3)?)
                }
                None => {
                    let r = Params::new(id, e.record("B_SPLINE_CURVE_WITH_KNOTS").unwrap_or(&e.records[0]), 9)?;
                    (r.shifted(1), r.shifted(6))
                }
            };
            let degree = head.uint(0)?;
            let poles = head.refs(1)?.into_iter().map(|q| self.point(q)).collect::<Result<Vec<_>, _>>()?;
            let knots =
                nurbs::expand_knots(&kr.ints(0)?, &kr.reals(1)?, degree, poles.len()).map_err(|m| bad(id, m))?;
            let mut weights = Vec::new();
            if let Some(rr) = e.record("RATIONAL_B_SPLINE_CURVE") {
                weights = Params::new(id, rr, 1)?.reals(0)?;
                if weights.len() != poles.len() || weights.iter().any(|x| x.is_nan() || *x <= 0.0) {
                    return Err(bad(id, "weights must be positive, one per control point"));
                }
            }
            return Ok(Curve::BSpline(Box::new(nurbs::Curve { degree, poles, weights, knots })));
        }
        let rec = &e.records[0];
        let p = Params::new(id, rec, 2)?;
        Ok(match rec.name.as_str() {
            "LINE" => {
                let p = p.at_least(3)?;
                let origin = self.point(p.reference(1)?)?;
                let v = p.reference(2)?;
                let ve = self.get(id, v)?;
                let vr = ve.record("VECTOR").ok_or_else(|| bad(v, "not a VECTOR"))?;
                let dir = self.direction(Params::new(v, vr, 3)?.reference(1)?)?;
                let dir = dir.try_normalize().ok_or_else(|| bad(v, "a zero direction"))?;
                Curve::Line { origin, dir }
            }
            "CIRCLE" => Curve::Circle(self.frame(p.at_least(3)?.reference(1)?)?, self.length(&p, 2)?),
            "ELLIPSE" => {
                let p = p.at_least(4)?;
                Curve::Ellipse(self.frame(p.reference(1)?)?, self.length(&p, 2)?, self.length(&p, 3)?)
            }
            "SURFACE_CURVE" | "SEAM_CURVE" => self.curve(p.reference(1)?)?,
            other => return Err(StepError::Unsupported { id, entity: other.to_string() }),
        })
    }
}

/// The parameters of one record, with typed accessors whose errors name the instance.
struct Params<'a> {
    id: u64,
    v: &'a [Param],
}

fn as_real(p: &Param) -> Option<f64> {
    match p {
        Param::Real(x) => Some(*x),
        Param::Int(i) => Some(*i as f64),
        Param::Typed(_, inner) => as_real(inner),
        _ => None,
    }
}

impl<'a> Params<'a> {
    fn new(id: u64, rec: &'a Record, at_least: usize) -> Result<Self, StepError> {
        Params { id, v: &rec.params }.at_least_named(at_least, &rec.name)
    }

    fn at_least_named(self, n: usize, name: &str) -> Result<Self, StepError> {
        if self.v.len() < n {
            return Err(bad(self.id, format!("{name} has {} parameters, expected {n}", self.v.len())));
        }
        Ok(self)
    }

    fn at_least(&self, n: usize) -> Result<Self, StepError> {
        Params { id: self.id, v: self.v }.at_least_named(n, "the entity")
    }

    fn shifted(&self, k: usize) -> Self {
        Params { id: self.id, v: self.v.get(k..).unwrap_or(&[]) }
    }

    fn at(&self, k: usize) -> Result<&'a Param, StepError> {
        self.v.get(k).ok_or_else(|| bad(self.id, format!("parameter {} is missing", k + 1)))
    }

    fn is_null(&self, k: usize) -> bool {
        matches!(self.v.get(k), Some(Param::Null) | None)
    }

    fn reference(&self, k: usize) -> Result<u64, StepError> {
        match self.at(k)? {
            Param::Ref(r) => Ok(*r),
            other => Err(bad(self.id, format!("parameter {} must be a reference, found {other:?}", k + 1))),
        }
    }

    fn boolean(&self, k: usize) -> Result<bool, StepError> {
        match self.at(k)? {
            Param::Enum(e) if e == "T" => Ok(true),
            Param::Enum(e) if e == "F" => Ok(false),
            other => Err(bad(self.id, format!("parameter {} must be .T. or .F., found {other:?}", k + 1))),
        }
    }

    fn real(&self, k: usize) -> Result<f64, StepError> {
        as_real(self.at(k)?).ok_or_else(|| bad(self.id, format!("parameter {} must be a number", k + 1)))
    }

    fn uint(&self, k: usize) -> Result<usize, StepError> {
        match self.at(k)? {
            Param::Int(i) if (0..=1_000_000).contains(i) => Ok(*i as usize),
            other => Err(bad(self.id, format!("parameter {} must be a non-negative integer, found {other:?}", k + 1))),
        }
    }

    fn list(&self, k: usize) -> Result<&'a [Param], StepError> {
        match self.at(k)? {
            Param::List(l) => Ok(l),
            other => Err(bad(self.id, format!("parameter {} must be a list, found {other:?}", k + 1))),
        }
    }

    fn refs(&self, k: usize) -> Result<Vec<u64>, StepError> {
        self.list(k)?
            .iter()
            .map(|p| match p {
                Param::Ref(r) => Ok(*r),
                _ => Err(bad(self.id, format!("parameter {} must be a list of references", k + 1))),
            })
            .collect()
    }

    fn reals(&self, k: usize) -> Result<Vec<f64>, StepError> {
        self.list(k)?
            .iter()
            .map(|p| {
                as_real(p)
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| bad(self.id, format!("parameter {} must be a list of numbers", k + 1)))
            })
            .collect()
    }

    fn ints(&self, k: usize) -> Result<Vec<i64>, StepError> {
        self.list(k)?
            .iter()
            .map(|p| match p {
                Param::Int(i) => Ok(*i),
                _ => Err(bad(self.id, format!("parameter {} must be a list of integers", k + 1))),
            })
            .collect()
    }
}

/// Millimetres per unit of an SI unit record `SI_UNIT(prefix, name)` named `base`.
fn si_factor(id: u64, e: &Entity, base: &str, base_factor: f64) -> Result<Option<f64>, StepError> {
    let Some(si) = e.record("SI_UNIT") else { return Ok(None) };
    let p = Params::new(id, si, 2)?;
    match p.at(1)? {
        Param::Enum(n) if n == base => {}
        _ => return Ok(None),
    }
    let prefix = match p.at(0)? {
        Param::Enum(x) => match x.as_str() {
            "MILLI" => 1e-3,
            "CENTI" => 1e-2,
            "DECI" => 1e-1,
            "MICRO" => 1e-6,
            "KILO" => 1e3,
            other => return Err(bad(id, format!("unit prefix {other} is not supported"))),
        },
        _ => 1.0,
    };
    Ok(Some(prefix * base_factor))
}

/// The factor of a unit entity (SI or conversion based), in the SI base scaled by `base_factor`.
fn unit_factor(table: &Table, id: u64, base: &str, base_factor: f64, depth: usize) -> Result<(f64, String), StepError> {
    let e = table.get(&id).ok_or_else(|| bad(id, "the unit is not defined"))?;
    if let Some(f) = si_factor(id, e, base, base_factor)? {
        let name = match f {
            f if f == 1.0 && base == "METRE" => "millimetre".to_string(),
            _ => format!("{}×{}", f / base_factor, base.to_ascii_lowercase()),
        };
        return Ok((f, name));
    }
    if let Some(cb) = e.record("CONVERSION_BASED_UNIT") {
        if depth > 4 {
            return Err(bad(id, "conversion-based units nested too deeply"));
        }
        let p = Params::new(id, cb, 2)?;
        let name = match p.at(0)? {
            Param::Str(s) => s.clone(),
            _ => "?".into(),
        };
        let m = p.reference(1)?;
        let me = table.get(&m).ok_or_else(|| bad(id, format!("refers to #{m}, which is not defined")))?;
        let mrec = me
            .records
            .iter()
            .find(|r| r.name.ends_with("MEASURE_WITH_UNIT"))
            .ok_or_else(|| bad(m, "not a measure with unit"))?;
        let mp = Params::new(m, mrec, 2)?;
        let (inner, _) = unit_factor(table, mp.reference(1)?, base, base_factor, depth + 1)?;
        let f = mp.real(0)? * inner;
        if !(f.is_finite() && f > 0.0) {
            return Err(bad(m, "the conversion factor must be positive"));
        }
        return Ok((f, name));
    }
    Err(bad(id, format!("{} is not a unit this reader knows", e.name())))
}

/// The unit with record `kind` the representation context assigns (GLOBAL_UNIT_ASSIGNED_CONTEXT),
/// else the first such unit of the file.
fn assigned_unit(table: &Table, kind: &str) -> Option<u64> {
    let has = |id: &u64| table.get(id).is_some_and(|e| e.record(kind).is_some());
    let assigned =
        table.values().filter_map(|e| e.record("GLOBAL_UNIT_ASSIGNED_CONTEXT")).find_map(|r| match r.params.first() {
            Some(Param::List(l)) => l.iter().find_map(|p| match p {
                Param::Ref(id) if has(id) => Some(*id),
                _ => None,
            }),
            _ => None,
        });
    assigned.or_else(|| table.iter().find(|(_, e)| e.record(kind).is_some()).map(|(&id, _)| id))
}

/// Millimetres per file length unit and its name.
fn length_unit(table: &Table) -> Result<(f64, String), StepError> {
    match assigned_unit(table, "LENGTH_UNIT") {
        Some(id) => unit_factor(table, id, "METRE", 1e3, 0),
        None => Ok((1.0, "assumed millimetre".into())),
    }
}

/// Radians per plane-angle unit.
fn angle_unit(table: &Table) -> Result<f64, StepError> {
    match assigned_unit(table, "PLANE_ANGLE_UNIT") {
        Some(id) => Ok(unit_factor(table, id, "RADIAN", 1.0, 0)?.0),
        None => Ok(1.0),
    }
}
