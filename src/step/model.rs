//! Instance table → typed B-rep: faces with their exact surfaces and bounds, edges with their
//! 3D curves and end vertices, in millimetres.
//!
//! Read: ADVANCED_FACE (and FACE_SURFACE) with FACE_OUTER_BOUND / FACE_BOUND of EDGE_LOOPs
//! (a VERTEX_LOOP, a sphere's pole or a cone's apex, is kept as a point the tessellator closes
//! the face at); ORIENTED_EDGE, EDGE_CURVE,
//! VERTEX_POINT; surfaces PLANE, CYLINDRICAL_, CONICAL_, SPHERICAL_, TOROIDAL_SURFACE and
//! B_SPLINE_SURFACE_WITH_KNOTS (simple or complex, RATIONAL_B_SPLINE_SURFACE too); curves LINE,
//! CIRCLE, ELLIPSE, B_SPLINE_CURVE_WITH_KNOTS (rational too), SURFACE_CURVE / SEAM_CURVE (their 3D
//! curve). PCURVEs are not read: the tessellator inverts the 3D edge samples onto the surface.
//! Units: the LENGTH_UNIT the representation context assigns (SI with prefix, or CONVERSION_BASED_UNIT such as INCH) and the
//! PLANE_ANGLE_UNIT (radian or degree); without one, millimetres and radians.
//! Assembly placements (MAPPED_ITEM, ITEM_DEFINED_TRANSFORMATION) are not applied: every face is
//! read in the coordinates it is written in.

use super::geom::{Curve, Frame, Surface};
use super::nurbs;
use super::parse::{Entity, Param, Record, Table};
use super::StepError;
use glam::DVec3;
use std::collections::BTreeMap;

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
        let curve = self.curve(p.reference(3)?)?;
        Ok(Edge { id, start, end, curve, same_sense: p.boolean(4)? })
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
