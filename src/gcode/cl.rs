//! Neutral cutter-location data (APT CLSF style) and its reader.

use super::{header_lines, sanitize_comment, Fmt, GcodeOptions, MAX_NAME_CHARS};
use crate::toolpath::{ToolShape, Toolpath};
use glam::DVec3;

pub(super) fn write(toolpath: &Toolpath, options: &GcodeOptions) -> String {
    let f = Fmt { decimals: options.decimals };
    let ijk = options.decimals + 2;
    let tool = toolpath.tool;
    let mut out = String::new();
    let mut line = |s: &str| {
        out.push_str(s);
        out.push('\n');
    };
    line(&format!("PARTNO {}", sanitize_comment(&options.part_name, MAX_NAME_CHARS)));
    line("$$ slitpath cutter-location data: GOTO/tool tip x,y,z, unit tool axis i,j,k; mm, mm/min");
    // The part line is PARTNO's; the others become comments.
    for l in header_lines(toolpath, options, &f).iter().skip(1) {
        line(&format!("$$ {l}"));
    }
    line("UNITS/MM");
    line("MULTAX/ON");
    line(&format!("LOADTL/{}", tool.number));
    match tool.shape {
        ToolShape::Ball => line(&format!("CUTTER/{},{}", f.num(2.0 * tool.radius_mm), f.num(tool.radius_mm))),
        // APT's 7-parameter cutter d, r, e, f, a, b, h: tip diameter, no corner radius, the
        // corner on the tip circle, flat bottom, the flank's taper from the axis, flute length.
        ToolShape::Cone { tip_radius_mm, top_radius_mm, flute_length_mm } => line(&format!(
            "CUTTER/{},0,{},0,0,{},{}",
            f.num(2.0 * tip_radius_mm),
            f.num(tip_radius_mm),
            f.with(super::cone_taper_deg(tip_radius_mm, top_radius_mm, flute_length_mm), ijk),
            f.num(flute_length_mm)
        )),
    }
    line(&format!("SPINDL/RPM,{},CLW", f.with(tool.spindle_rpm, 1)));
    let mut fedrat: Option<String> = None;
    for m in &toolpath.moves {
        if m.kind.is_rapid() {
            line("RAPID");
        } else {
            let feed = f.with(m.feed_mm_min, 1);
            if fedrat.as_ref() != Some(&feed) {
                line(&format!("FEDRAT/{feed}"));
                fedrat = Some(feed);
            }
        }
        let (p, a) = (m.tip, m.axis);
        line(&format!(
            "GOTO/{},{},{},{},{},{}",
            f.num(p.x),
            f.num(p.y),
            f.num(p.z),
            f.with(a.x, ijk),
            f.with(a.y, ijk),
            f.with(a.z, ijk)
        ));
    }
    line("SPINDL/OFF");
    line("END");
    line("FINI");
    out
}

/// One `GOTO` of CL data.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClMove {
    /// Preceded by `RAPID` (which applies to the next `GOTO` only).
    pub rapid: bool,
    /// The modal `FEDRAT` of a feed move, mm/min (None for rapids).
    pub feed_mm_min: Option<f64>,
    pub tip: DVec3,
    /// The tool axis (`0, 0, 1` for a 3-value `GOTO`).
    pub axis: DVec3,
}

/// CL data as read by [`parse_cl`].
#[derive(Clone, Debug, PartialEq, Default)]
pub struct ClProgram {
    pub part_name: String,
    pub multax: bool,
    pub tool_number: Option<u32>,
    pub cutter_diameter_mm: Option<f64>,
    pub corner_radius_mm: Option<f64>,
    /// Every number of the `CUTTER` statement, in order (APT: d, r, e, f, a, b, h).
    pub cutter: Vec<f64>,
    pub spindle_rpm: Option<f64>,
    pub moves: Vec<ClMove>,
}

/// A CL data statement [`parse_cl`] could not read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("CL data line {line}: {reason}")]
pub struct ClError {
    /// 1-based line number.
    pub line: usize,
    pub reason: String,
}

/// Reads CL data as written by the `cl` post: `PARTNO`, `$$` comments, `UNITS/MM` (other units
/// are an error), `MULTAX/ON|OFF`, `LOADTL/n`, `CUTTER/d[,r,…]`, `SPINDL/…`, `FEDRAT/f[,MMPM]`,
/// `RAPID`, `GOTO/x,y,z[,i,j,k]`, `END`, `FINI` (required; anything after it is ignored).
/// Statement words are case-insensitive; blank lines are skipped.
pub fn parse_cl(text: &str) -> Result<ClProgram, ClError> {
    let mut program = ClProgram::default();
    let (mut rapid, mut feed) = (false, None);
    let mut lines = 0;
    for (k, raw) in text.lines().enumerate() {
        lines = k + 1;
        let err = |reason: String| ClError { line: k + 1, reason };
        let s = raw.trim();
        if s.is_empty() || s.starts_with("$$") {
            continue;
        }
        if let Some(name) = s.get(..6).filter(|w| w.eq_ignore_ascii_case("PARTNO")).map(|_| &s[6..]) {
            program.part_name = name.trim().to_string();
            continue;
        }
        let (word, args) = match s.split_once('/') {
            Some((w, a)) => (w.trim().to_ascii_uppercase(), a.split(',').map(str::trim).collect::<Vec<_>>()),
            None => (s.to_ascii_uppercase(), Vec::new()),
        };
        let numbers = |args: &[&str]| -> Result<Vec<f64>, ClError> {
            args.iter()
                .map(|a| match a.parse::<f64>() {
                    Ok(v) if v.is_finite() => Ok(v),
                    _ => Err(err(format!("'{a}' is not a finite number in {word}"))),
                })
                .collect()
        };
        match word.as_str() {
            "UNITS" => {
                if !(args.len() == 1 && args[0].eq_ignore_ascii_case("MM")) {
                    return Err(err(format!("only UNITS/MM is supported, got '{s}'")));
                }
            }
            "MULTAX" => match args.first().map(|a| a.to_ascii_uppercase()).as_deref() {
                Some("ON") | None => program.multax = true,
                Some("OFF") => program.multax = false,
                _ => return Err(err(format!("MULTAX takes ON or OFF, got '{s}'"))),
            },
            "LOADTL" => {
                let n = args.first().and_then(|a| a.parse::<u32>().ok());
                program.tool_number = Some(n.ok_or_else(|| err(format!("LOADTL needs a tool number, got '{s}'")))?);
            }
            "CUTTER" => {
                let v = numbers(&args)?;
                if v.is_empty() {
                    return Err(err("CUTTER needs a diameter".to_string()));
                }
                program.cutter_diameter_mm = Some(v[0]);
                program.corner_radius_mm = v.get(1).copied();
                program.cutter = v;
            }
            "SPINDL" => {
                if let Some(i) = args.iter().position(|a| a.eq_ignore_ascii_case("RPM")) {
                    let speed = args.get(i + 1).ok_or_else(|| err(format!("SPINDL/RPM needs a speed, got '{s}'")))?;
                    program.spindle_rpm = Some(numbers(&[speed])?[0]);
                }
            }
            "FEDRAT" => match args.first().map(|a| a.parse::<f64>()) {
                Some(Ok(v)) if v > 0.0 && v.is_finite() => feed = Some(v),
                _ => return Err(err(format!("FEDRAT needs a finite feed > 0, got '{s}'"))),
            },
            "RAPID" => rapid = true,
            "GOTO" => {
                let v = numbers(&args)?;
                let axis = match v.len() {
                    3 => DVec3::Z,
                    6 => DVec3::new(v[3], v[4], v[5]),
                    n => return Err(err(format!("GOTO takes 3 or 6 numbers, got {n}"))),
                };
                if !rapid && feed.is_none() {
                    return Err(err("GOTO at feed before any FEDRAT".to_string()));
                }
                let tip = DVec3::new(v[0], v[1], v[2]);
                program.moves.push(ClMove { rapid, feed_mm_min: if rapid { None } else { feed }, tip, axis });
                rapid = false;
            }
            "END" => {}
            "FINI" => return Ok(program),
            _ => return Err(err(format!("unknown statement '{s}'"))),
        }
    }
    Err(ClError { line: lines + 1, reason: "missing FINI: the CL data is truncated".to_string() })
}
