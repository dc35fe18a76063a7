//! Stage 9 — `gcode`: post-processors that turn a [`Toolpath`] into a program text.
//!
//! What it computes (DESIGN.md "gcode", issue 5 "posts"): deterministic text — fixed decimals,
//! `\n` line ends, no hash-map order, the same bytes on every target — for one of four posts:
//!
//! - [`Post::LinuxCnc`] (default) and [`Post::Grbl`]: 3-axis G-code. Header comment block (part
//!   name, the tool, the caller's key/value lines), `G21 G90 G17 G94 G40` (+ `G49` and
//!   `G64 P…` path blending for LinuxCNC; GRBL has no `G64`, and `G49` is its power-on state and
//!   missing before GRBL 0.9), the tool change `T… M6` + `G43 H…` (LinuxCNC only: GRBL has no
//!   tool changer and rejects `M6`), `S… M3`, `G0 Z<safe>`, the moves, `M5`, `M30`. Tool tips
//!   are programmed: the tool length offset comes from the machine's tool table (`G43 H…`).
//!   The toolpath's tool axis must be +Z ([`GcodeError::NotThreeAxis`] otherwise).
//! - [`Post::Ac`]: 5-axis table-table machine, A tilting about X and C rotating about Z, whose
//!   controller does tool-centre-point control (LinuxCNC TCP kinematics such as
//!   `xyzac-trt-kins` in TCP mode; `G43.4` on other controls — not emitted, LinuxCNC 2.9 does not
//!   know it). Output: tool-tip X Y Z in the part frame plus A C in degrees, LinuxCNC dialect.
//!   Convention ([`ac`]): the tool axis in the part frame is `Rz(C)·Rx(A)·(0, 0, 1) = (sin A sin C,
//!   −sin A cos C, cos A)`; C is unwrapped (continuous, may pass ±360°), |A| ≤
//!   [`ac::A_LIMIT_DEG`], and near the singular pose (|A| < [`ac::SINGULAR_DEG`]) C is held.
//!   A machine whose rotary axes turn the other way negates A and/or C in its configuration.
//! - [`Post::Cl`]: neutral cutter-location data in the style of APT CLSF (`PARTNO`, `UNITS/MM`,
//!   `MULTAX/ON`, `LOADTL`, `CUTTER/d,r`, `SPINDL`, `FEDRAT/f`, `RAPID`, `GOTO/x,y,z,i,j,k` with
//!   the tool tip and unit axis, `FINI`) for a portal's own post-processor; [`parse_cl`] reads it
//!   back.
//!
//! G-code words that did not change are skipped (modal `G0`/`G1`, `F`, unchanged coordinates at
//! the output precision); a move that changes nothing at that precision is dropped, so no empty
//! move line is ever written. Coordinates have `decimals` decimals, A C too, CL direction
//! cosines `decimals + 2`, feeds (mm/min) and spindle speeds 1 decimal; `-0.0000` is written
//! `0.0000`.
//!
//! Comments. Everything the caller gives (part name, header keys and values) is sanitised by
//! [`sanitize_comment`]: no parentheses, semicolons, `$`, control characters or non-ASCII can
//! reach the output, and the text is truncated. Every comment line starts with a fixed word
//! (`part:` or `- `) so no caller text can turn it into a LinuxCNC active comment (`MSG,`,
//! `DEBUG,`, `LOGOPEN,`, `PROBEOPEN` …).
//!
//! Preconditions (each fault is a [`GcodeError`]): `decimals` in 1..=8, a non-empty toolpath
//! with finite tips, unit axes, positive feeds, a tool number ≥ 1, positive radius and spindle
//! speed; post-specific: 3-axis posts need the +Z axis, the AC post |A| ≤ its limit.

// `!(x > 0.0)` is deliberate throughout: NaN must fail every validity test.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod ac;
mod cl;
mod ngc;

pub use cl::{parse_cl, ClError, ClMove, ClProgram};

use crate::toolpath::{ToolShape, Toolpath};

/// The post-processors.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize)]
pub enum Post {
    /// LinuxCNC 3-axis G-code.
    #[default]
    LinuxCnc,
    /// GRBL 3-axis G-code (a subset of LinuxCNC's dialect).
    Grbl,
    /// 5-axis table-table A/C with tool-centre-point control (LinuxCNC dialect).
    Ac,
    /// APT-style cutter-location data.
    Cl,
}

impl Post {
    /// Every post, in a fixed order.
    pub const ALL: [Post; 4] = [Post::LinuxCnc, Post::Grbl, Post::Ac, Post::Cl];

    /// The post's command-line name: `linuxcnc`, `grbl`, `ac`, `cl`.
    pub fn name(self) -> &'static str {
        match self {
            Post::LinuxCnc => "linuxcnc",
            Post::Grbl => "grbl",
            Post::Ac => "ac",
            Post::Cl => "cl",
        }
    }

    /// Usual file extension of the post's output.
    pub fn extension(self) -> &'static str {
        match self {
            Post::LinuxCnc | Post::Ac => "ngc",
            Post::Grbl => "nc",
            Post::Cl => "cl",
        }
    }
}

impl std::fmt::Display for Post {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Post {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Post::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| format!("unknown post '{s}': use linuxcnc, grbl, ac or cl"))
    }
}

/// Options of [`gcode`]. Defaults in brackets.
#[derive(Clone, Debug, PartialEq)]
pub struct GcodeOptions {
    /// Post-processor [LinuxCnc].
    pub post: Post,
    /// Decimals of coordinates and angles, 1..=8 [4].
    pub decimals: usize,
    /// Part name for the header (sanitised) ["part"].
    pub part_name: String,
    /// Key/value lines for the header, in the given order (sanitised) [none].
    pub header: Vec<(String, String)>,
    /// LinuxCNC path blending tolerance `G64 P…`, mm; 0 writes `G61` (exact path). Used by the
    /// LinuxCNC and AC posts [0.005].
    pub blend_tolerance_mm: f64,
}

impl Default for GcodeOptions {
    fn default() -> Self {
        GcodeOptions {
            post: Post::LinuxCnc,
            decimals: 4,
            part_name: "part".to_string(),
            header: Vec::new(),
            blend_tolerance_mm: 0.005,
        }
    }
}

/// Errors of [`gcode`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GcodeError {
    #[error("decimals = {decimals} is invalid: use 1 to 8")]
    BadDecimals { decimals: usize },
    #[error("blend_tolerance_mm = {value} is invalid: use a finite number ≥ 0")]
    BadBlendTolerance { value: f64 },
    #[error("the toolpath has no move")]
    EmptyToolpath,
    #[error("move {index} has a non-finite tip or axis")]
    NonFiniteMove { index: usize },
    #[error("move {index} has a tool axis of length {length}: axes must be unit vectors")]
    NotUnitAxis { index: usize, length: f64 },
    #[error("move {index} has feed {feed} mm/min: feeds must be > 0")]
    BadFeed { index: usize, feed: f64 },
    #[error("tool {field} = {value} is invalid: it must be > 0 (tool numbers ≥ 1)")]
    BadTool { field: &'static str, value: f64 },
    #[error("the {post} post is 3-axis but move {index} has tool axis ({x}, {y}, {z}): plan with the +Z axis or use the ac or cl post")]
    NotThreeAxis { post: Post, index: usize, x: f64, y: f64, z: f64 },
    #[error(
        "move {index} needs A = {a_deg}°, beyond the AC machine's ±{limit_deg}°: the tool axis tilts too far from +Z"
    )]
    AOutOfRange { index: usize, a_deg: f64, limit_deg: f64 },
}

/// Writes the program text of `toolpath` for `options.post` (see the module docs).
pub fn gcode(toolpath: &Toolpath, options: &GcodeOptions) -> Result<String, GcodeError> {
    check(toolpath, options)?;
    match options.post {
        Post::LinuxCnc | Post::Grbl | Post::Ac => ngc::write(toolpath, options),
        Post::Cl => Ok(cl::write(toolpath, options)),
    }
}

fn check(toolpath: &Toolpath, options: &GcodeOptions) -> Result<(), GcodeError> {
    if !(1..=8).contains(&options.decimals) {
        return Err(GcodeError::BadDecimals { decimals: options.decimals });
    }
    if !(options.blend_tolerance_mm >= 0.0 && options.blend_tolerance_mm.is_finite()) {
        return Err(GcodeError::BadBlendTolerance { value: options.blend_tolerance_mm });
    }
    if toolpath.moves.is_empty() {
        return Err(GcodeError::EmptyToolpath);
    }
    let tool = &toolpath.tool;
    if tool.number == 0 {
        return Err(GcodeError::BadTool { field: "number", value: 0.0 });
    }
    for (field, value) in [("radius_mm", tool.radius_mm), ("spindle_rpm", tool.spindle_rpm)] {
        if !(value > 0.0 && value.is_finite()) {
            return Err(GcodeError::BadTool { field, value });
        }
    }
    if let ToolShape::Cone { tip_radius_mm, top_radius_mm, flute_length_mm } = tool.shape {
        for (field, value) in
            [("tip_radius_mm", tip_radius_mm), ("top_radius_mm", top_radius_mm), ("flute_length_mm", flute_length_mm)]
        {
            if !(value > 0.0 && value.is_finite()) {
                return Err(GcodeError::BadTool { field, value });
            }
        }
    }
    for (index, m) in toolpath.moves.iter().enumerate() {
        if !(m.tip.is_finite() && m.axis.is_finite()) {
            return Err(GcodeError::NonFiniteMove { index });
        }
        let length = m.axis.length();
        if !((length - 1.0).abs() <= 1e-9) {
            return Err(GcodeError::NotUnitAxis { index, length });
        }
        if !(m.feed_mm_min > 0.0 && m.feed_mm_min.is_finite()) {
            return Err(GcodeError::BadFeed { index, feed: m.feed_mm_min });
        }
    }
    Ok(())
}

/// Longest sanitised part name, characters.
pub const MAX_NAME_CHARS: usize = 64;
/// Longest sanitised header line (key and value), characters.
pub const MAX_HEADER_CHARS: usize = 120;

/// Makes `text` safe inside a G-code comment `( … )`, an APT `$$` comment or `PARTNO`: `(` `)`
/// become `[` `]`, `;` becomes `,`, `$` becomes `S`, control characters (newlines, tabs)
/// become spaces, every other non-ASCII or non-printable character becomes `?`; runs of spaces
/// collapse, the ends are trimmed, and the result is cut to `max_chars` characters.
pub fn sanitize_comment(text: &str, max_chars: usize) -> String {
    let mut out = String::with_capacity(text.len().min(max_chars));
    for ch in text.chars() {
        let c = match ch {
            '(' => '[',
            ')' => ']',
            ';' => ',',
            '$' => 'S',
            c if c.is_control() || c.is_whitespace() => ' ',
            c if c.is_ascii_graphic() => c,
            _ => '?',
        };
        if c == ' ' && (out.is_empty() || out.ends_with(' ')) {
            continue;
        }
        out.push(c);
    }
    let mut out: String = out.trim_end().chars().take(max_chars).collect();
    out.truncate(out.trim_end().len());
    out
}

/// The header lines common to every post (without comment delimiters): part, tool, caller's.
fn header_lines(toolpath: &Toolpath, options: &GcodeOptions, f: &Fmt) -> Vec<String> {
    let tool = &toolpath.tool;
    let tool_line = match tool.shape {
        ToolShape::Ball => format!(
            "- tool: T{} ball-end D{} R{} at {} rpm",
            tool.number,
            f.num(2.0 * tool.radius_mm),
            f.num(tool.radius_mm),
            f.with(tool.spindle_rpm, 1)
        ),
        ToolShape::Cone { tip_radius_mm, top_radius_mm, flute_length_mm } => format!(
            "- tool: T{} conical flank cutter tip D{} top D{} flute L{} taper {} deg at {} rpm",
            tool.number,
            f.num(2.0 * tip_radius_mm),
            f.num(2.0 * top_radius_mm),
            f.num(flute_length_mm),
            f.num(cone_taper_deg(tip_radius_mm, top_radius_mm, flute_length_mm)),
            f.with(tool.spindle_rpm, 1)
        ),
    };
    let mut lines = vec![format!("part: {}", sanitize_comment(&options.part_name, MAX_NAME_CHARS)), tool_line];
    for (k, v) in &options.header {
        let line = format!("{}: {}", sanitize_comment(k, MAX_HEADER_CHARS), sanitize_comment(v, MAX_HEADER_CHARS));
        lines.push(format!("- {}", sanitize_comment(&line, MAX_HEADER_CHARS)));
    }
    lines
}

/// The half-angle of a conical flute, degrees: atan((top − tip) / flute length).
pub fn cone_taper_deg(tip_radius_mm: f64, top_radius_mm: f64, flute_length_mm: f64) -> f64 {
    crate::num::atan2(top_radius_mm - tip_radius_mm, flute_length_mm).to_degrees()
}

/// Fixed-decimal number formatting (deterministic on every target: Rust's own float printing).
struct Fmt {
    decimals: usize,
}

impl Fmt {
    fn with(&self, v: f64, decimals: usize) -> String {
        let mut s = String::new();
        self.push_with(&mut s, v, decimals);
        s
    }
    fn num(&self, v: f64) -> String {
        self.with(v, self.decimals)
    }

    /// [`Fmt::with`] appended to `s` (the posts reuse one buffer per word: a string per number
    /// was a third of the wasm post's time, in its allocator).
    fn push_with(&self, s: &mut String, v: f64, decimals: usize) {
        // Integer digits: formatting floats exactly was a tenth of a 40k-face plan.
        let x = v * 10f64.powi(decimals as i32);
        if decimals <= 9 && x.abs() < 9.0e15 {
            // The digits by hand, last first (through write! they took a third of the post).
            let n = x.round() as i64;
            let mut a = n.unsigned_abs();
            let mut buf = [0u8; 32];
            let mut i = buf.len();
            for k in 0.. {
                if k == decimals && k > 0 {
                    i -= 1;
                    buf[i] = b'.';
                }
                i -= 1;
                buf[i] = b'0' + (a % 10) as u8;
                a /= 10;
                if a == 0 && k >= decimals {
                    break;
                }
            }
            if n < 0 {
                i -= 1;
                buf[i] = b'-';
            }
            s.extend(buf[i..].iter().map(|&b| b as char));
            return;
        }
        let f = format!("{v:.decimals$}");
        match f.strip_prefix('-') {
            Some(rest) if rest.bytes().all(|b| b == b'0' || b == b'.') => s.push_str(rest),
            _ => s.push_str(&f),
        }
    }
    fn push_num(&self, s: &mut String, v: f64) {
        self.push_with(s, v, self.decimals)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_have_fixed_decimals_and_no_negative_zero() {
        let f = Fmt { decimals: 4 };
        assert_eq!(f.num(1.0), "1.0000");
        assert_eq!(f.num(-0.00001), "0.0000");
        assert_eq!(f.num(-0.0), "0.0000");
        assert_eq!(f.num(-1.23456), "-1.2346");
        assert_eq!(f.with(0.5, 6), "0.500000");
        assert_eq!(f.with(12.25, 1), "12.3");
        assert_eq!(f.with(-7.0, 0), "-7");
        assert_eq!(f.num(123456.78905), "123456.7891");
        assert_eq!(f.num(1e300), format!("{:.4}", 1e300));
    }

    #[test]
    fn numbers_match_the_format_machinery_on_many_values() {
        // The rounding the post promises (x.round() on the scaled value), printed by fmt.
        let oracle = |v: f64, d: usize| {
            let n = (v * 10f64.powi(d as i32)).round() as i64;
            let (p, a, sign) = (10u64.pow(d as u32), n.unsigned_abs(), if n < 0 { "-" } else { "" });
            if d == 0 {
                format!("{sign}{a}")
            } else {
                format!("{sign}{}.{:0d$}", a / p, a % p)
            }
        };
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        for k in 0..20_000 {
            x = x.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            let unit = (x >> 11) as f64 / (1u64 << 53) as f64;
            let v = (unit - 0.5) * 10f64.powi(k % 12 - 4);
            for d in 0..=8 {
                assert_eq!(Fmt { decimals: d }.num(v), oracle(v, d), "{v} at {d} decimals");
            }
        }
    }

    #[test]
    fn sanitiser_removes_everything_that_could_end_a_comment() {
        let s = sanitize_comment("a(b)c;d\ne\r\tf $ü  g  ", 100);
        assert_eq!(s, "a[b]c,d e f S? g");
        assert_eq!(sanitize_comment("  ", 10), "");
        assert_eq!(sanitize_comment("abcdef", 3), "abc");
        assert_eq!(sanitize_comment("ab   cdef", 3), "ab");
    }

    #[test]
    fn post_names_round_trip() {
        for p in Post::ALL {
            assert_eq!(p.name().parse::<Post>(), Ok(p));
        }
        assert!("fanuc".parse::<Post>().is_err());
    }
}
