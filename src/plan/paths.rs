//! Which path a plan writes, judged by its own verification.
//!
//! The spacing proves the scallop limit at the points it tests (the meridians' cusps, the gate's
//! points along each band), not everywhere. A narrow peak between its tests can remain a few
//! hundredths of h over: the lift of balls beside a shallow crease that it leaves to its margin,
//! a ring turning round a corner. The verifier samples the whole surface. So:
//!
//! 1. The optimised field's path (seed 003) is planned and verified. Where it leaves more than
//!    h outside the facet valleys (where the facets alone leave more, and the plan has warned),
//!    or its plan failed, the conformal map's path (seed 000) is planned too and the better one
//!    kept.
//! 2. Where the path kept still leaves more than h (but at most [`MAX_RETRY_EXCESS`] h), its
//!    rings are spaced again, once, on the same field, for a cusp smaller in proportion to the
//!    excess ([`RETRY_AIM`]), and the better of the two kept. Retrying the optimised field's
//!    path first was tried: on gen114 of the generated parts its excess (1.10 h, the conformal
//!    map's 1.02 h) asked for 12 % smaller cusps, and its path came out 11 % longer than the
//!    conformal map's (6 % longer than that one spaced again).
//!
//! 3. With `--spread need` the field's path spread by each meridian's need ([`crate::spread`])
//!    comes first. When it keeps h as first spaced it is written, and the unspread path is not
//!    planned. Else it is spaced again as in 2, the unspread path is planned as in 1 and 2, and
//!    the shorter is written when both keep h, else the one that leaves less. (Stop 48 planned
//!    both always: on the first 60 generated parts of the sweep the spread path kept h as first
//!    spaced on 53, and was the longer on 7 of those, by 2.2 % at most. Its retry, kept without
//!    the comparison, was 7 % longer than the unspread path on gen028.)
//!
//! A part whose first path keeps h costs nothing more and gets the same G-code. The retries are
//! reported (`spacing_retries`), and so is the field kept (`optimise.path_field`).

use super::{OptimiseSummary, PathSummary, PlanError, PlanOptions, Planner, RingSpread, Timings};
use crate::origin::Origin;
use crate::slitmap::SlitMap;
use crate::spacing::{Rings, SpacingOptions};
use crate::spiral::{Spiral, SpiralOptions};
use crate::toolpath::Toolpath;
use crate::verify::{PathMetrics, Verification};
use serde::Serialize;

/// The scallop fraction the rings of an optimised field are spaced for (see
/// [`SpacingOptions::target_fraction`]; the conformal map's keep the default 0.95). An optimised
/// field's rings bend more between the meridians than the conformal map's circles, and the
/// spacing's tests between them are looser (the gate's levels pass up to h/4 under a peak): 0.95
/// left 1.01–1.1 h on a third of the generated parts, 0.92 on a sixth, for 1.5 % more path.
pub const OPTIMISED_TARGET_FRACTION: f64 = 0.92;

/// A retry spaces its rings for the first target times this over the excess (max / h): a peak
/// scales about as the cusps the spacing plans (both are set by the rings' distance), so the
/// retry's peak lands near this fraction of h.
pub const RETRY_AIM: f64 = 0.97;

/// A path leaving more than this many times h is not spaced again: an excess that large is not
/// the rings' margin but a region the path misses (a fold of the map at the pole: gen14 of the
/// generated parts from (−15, 20, 0) left 140 h, and its rings spaced for 0.006 h, 12 times the
/// path, still left 142 h). The sweep's retries were at 1.1–2.0 h. The report's warning says so.
pub const MAX_RETRY_EXCESS: f64 = 2.0;

/// What every path of one plan shares: the options, the progress callback, the clock and the
/// stage timings (summed over every path planned).
pub(super) struct Run<'a> {
    pub options: &'a PlanOptions,
    pub spiral_options: &'a SpiralOptions,
    pub stage: &'a mut dyn FnMut(usize),
    pub timings: &'a mut Timings,
    pub now: &'a dyn Fn() -> f64,
}

/// The field the rings are level sets of: the pole's slit map, optimised (seed 003) or not,
/// spread by each meridian's need ([`crate::spread`]) or not.
#[derive(Clone)]
pub(super) struct Field {
    pub map: SlitMap,
    pub optimised: bool,
    pub spread: bool,
}

impl Field {
    fn name(&self) -> &'static str {
        match (self.optimised, self.spread) {
            (true, false) => "tpsfo",
            (false, false) => "conformal",
            (true, true) => "tpsfo, spread",
            (false, true) => "conformal, spread",
        }
    }

    /// The scallop fraction this field's rings are spaced for first.
    fn target_fraction(&self) -> f64 {
        if self.optimised {
            OPTIMISED_TARGET_FRACTION
        } else {
            SpacingOptions::default().target_fraction
        }
    }
}

/// A path planned from one field (see [`Planner::finish`]).
pub(super) struct Finished {
    pub field: Field,
    /// What the report says of the optimisation (set by [`Planner::path_from`]).
    pub optimise: Option<OptimiseSummary>,
    pub rings: Rings,
    pub spiral: Spiral,
    pub toolpath: Toolpath,
    pub path: PathMetrics,
    pub summary: PathSummary,
    pub verification: Option<Verification>,
    pub gcode: String,
    /// The paths of this plan spaced again because an earlier one left more than h.
    pub retries: Vec<SpacingRetry>,
    /// With `--spread need`: the spread field's path and whether it was kept.
    pub spread: Option<SpreadSummary>,
}

/// The spread field's path ([`crate::spread`], `--spread need`) against the path of the field
/// without it (the plan report's `spread`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpreadSummary {
    /// Whether the spread field's path was written: it keeps h outside the facet valleys as
    /// first spaced (then the unspread path is not planned), or after a retry and is shorter than
    /// the unspread path, or it keeps h where that one does not, or leaves less.
    pub kept: bool,
    /// The spread field's path: its length and largest scallop outside the facet valleys over h
    /// (`None` when its plan failed, see `error`).
    pub length_mm: Option<f64>,
    pub max_over_h: Option<f64>,
    /// The path without the spread, planned when the spread one left more than h as first
    /// spaced: its length and largest scallop over h.
    pub unspread_length_mm: Option<f64>,
    pub unspread_max_over_h: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

/// A path whose verification left more than h outside the facet valleys, and its rings spaced
/// again for a smaller cusp (the plan report's `spacing_retries`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpacingRetry {
    /// `tpsfo` or `conformal` (either `, spread`): the field both paths follow.
    pub field: &'static str,
    /// The first path's target (fraction of h), the largest scallop it left outside the facet
    /// valleys over h, and its length.
    pub target_fraction: f64,
    pub max_over_h: f64,
    pub length_mm: f64,
    /// The same for the path spaced again (`None` when its plan failed, see `error`).
    pub retry_target_fraction: f64,
    pub retry_max_over_h: Option<f64>,
    pub retry_length_mm: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// Whether the path spaced again was kept (it keeps h, or leaves less than the first).
    pub kept: bool,
}

impl SpreadSummary {
    /// The spread path `fin`, kept at once: it keeps h.
    fn first(fin: &Finished, h: f64) -> Self {
        Self {
            kept: true,
            length_mm: Some(fin.summary.length_mm),
            max_over_h: Some(fin.max_over_h(h)),
            unspread_length_mm: None,
            unspread_max_over_h: None,
            error: None,
        }
    }
}

impl SpacingRetry {
    /// One line for the user (the CLI's note).
    pub fn describe(&self) -> String {
        let first = format!(
            "the {} path left {:.3} h outside the facet valleys; its rings spaced again for {:.3} h",
            self.field, self.max_over_h, self.retry_target_fraction
        );
        match (self.retry_max_over_h, self.retry_length_mm, &self.error) {
            (Some(max), Some(length), _) => format!(
                "{first} left {max:.3} h with {:+.1} % path: {}",
                100.0 * (length / self.length_mm - 1.0),
                if self.kept { "kept" } else { "not kept" }
            ),
            (_, _, Some(e)) => format!("{first} failed ({e}): the first kept"),
            _ => first,
        }
    }
}

impl Finished {
    /// The verified largest scallop outside the facet valleys over `h` (0 unverified).
    fn max_over_h(&self, h: f64) -> f64 {
        self.verification.as_ref().map_or(0.0, |v| v.max_scallop_outside_valleys_mm / h)
    }

    /// Whether the verified path leaves more than `h` outside the facet valleys.
    fn exceeds(&self, h: f64) -> bool {
        self.max_over_h(h) > 1.0
    }

    /// Whether this path keeps `h` where `other` does not, or, both leaving more, leaves less.
    fn better_than(&self, other: &Finished, h: f64) -> bool {
        let (a, b) = (self.max_over_h(h), other.max_over_h(h));
        (a <= 1.0 && b > 1.0) || (a > 1.0 && b > 1.0 && a < b)
    }

    /// This (conformal) path, kept instead of the optimised one `optimised` for `reason`: the
    /// report keeps the optimisation's figures and says why its path was not used.
    fn kept_instead_of(mut self, optimised: Finished, reason: String) -> Self {
        self.optimise = Some(OptimiseSummary {
            path_field: "conformal",
            fallback: Some(reason),
            optimised_length_mm: Some(optimised.summary.length_mm),
            ..optimised.optimise.unwrap_or_default()
        });
        self
    }

    /// This (conformal) path, planned because the optimised field's failed with `error`.
    fn kept_after_error(mut self, error: String) -> Self {
        self.optimise = Some(OptimiseSummary {
            path_field: "conformal",
            fallback: Some(format!("the optimised field's plan failed: {error}")),
            ..OptimiseSummary::default()
        });
        self
    }
}

impl Planner {
    /// The path written from the pole's slit map `map` (see the module docs).
    pub(super) fn path_from(
        &self,
        run: &mut Run,
        origin: &Origin,
        map: SlitMap,
        tpsfo: bool,
    ) -> Result<Finished, PlanError> {
        let h = run.options.scallop_mm;
        let conformal = tpsfo.then(|| map.clone());
        let field = self.field(run, origin, map, tpsfo);
        // With `--spread need` the spread field's path comes first: when it keeps h as first
        // spaced, it is written without planning the unspread one (step 3 of the module docs).
        let spread_first = match (&field, run.options.spread) {
            (Ok((field, optimise)), RingSpread::Need) => match self.spread_path(run, origin, field) {
                Ok(fin) if !fin.exceeds(h) && fin.retries.is_empty() => {
                    let summary = SpreadSummary::first(&fin, h);
                    return Ok(Finished { optimise: optimise.clone(), spread: Some(summary), ..fin });
                }
                spread => Some(spread),
            },
            _ => None,
        };
        let first = field.and_then(|(field, optimise)| {
            let target = field.target_fraction();
            Ok(Finished { optimise, ..self.finish(run, origin, field, target)? })
        });
        let chosen = match conformal {
            None => first,
            Some(conformal) => {
                let plain = |run: &mut Run| {
                    let (field, _) = self.field(run, origin, conformal, false)?;
                    let target = field.target_fraction();
                    self.finish(run, origin, field, target)
                };
                match first {
                    Ok(fin) if fin.exceeds(h) => match plain(run) {
                        Ok(plain) if plain.better_than(&fin, h) => {
                            let reason = format!(
                                "the optimised field's path left {:.3} h, the conformal map's {:.3} h",
                                fin.max_over_h(h),
                                plain.max_over_h(h)
                            );
                            Ok(plain.kept_instead_of(fin, reason))
                        }
                        _ => Ok(fin),
                    },
                    Ok(fin) => Ok(fin),
                    Err(e) => plain(run).map(|plain| plain.kept_after_error(e.to_string())),
                }
            }
        };
        let chosen = self.retried(run, origin, chosen?);
        Ok(match (run.options.spread, spread_first) {
            (RingSpread::None, _) => chosen,
            (RingSpread::Need, Some(spread)) => Self::spread_or(spread, chosen, h),
            // The field failed: the spread follows the one the path was planned from.
            (RingSpread::Need, None) => {
                let spread = self.spread_path(run, origin, &chosen.field);
                Self::spread_or(spread, chosen, h)
            }
        })
    }

    /// The path of `field` spread by each meridian's need ([`crate::spread`]), spaced again
    /// when it leaves more than h ([`Planner::retried`]).
    fn spread_path(&self, run: &mut Run, origin: &Origin, field: &Field) -> Result<Finished, PlanError> {
        let field = Field { spread: true, ..field.clone() };
        let target = field.target_fraction();
        let fin = self.finish(run, origin, field, target)?;
        Ok(self.retried(run, origin, fin))
    }

    /// The spread field's path `spread` when it is shorter and both keep h, or it keeps h where
    /// `fin` does not, or both leave more and it leaves less; else `fin`. Either way with the
    /// comparison reported.
    fn spread_or(spread: Result<Finished, PlanError>, fin: Finished, h: f64) -> Finished {
        let mut summary = SpreadSummary {
            kept: false,
            length_mm: None,
            max_over_h: None,
            unspread_length_mm: Some(fin.summary.length_mm),
            unspread_max_over_h: Some(fin.max_over_h(h)),
            error: None,
        };
        match spread {
            Ok(spread) => {
                summary.length_mm = Some(spread.summary.length_mm);
                summary.max_over_h = Some(spread.max_over_h(h));
                summary.kept = if spread.exceeds(h) || fin.exceeds(h) {
                    spread.better_than(&fin, h)
                } else {
                    spread.summary.length_mm < fin.summary.length_mm
                };
                let retries: Vec<SpacingRetry> = spread.retries.iter().chain(&fin.retries).cloned().collect();
                if summary.kept {
                    return Finished { optimise: fin.optimise, retries, spread: Some(summary), ..spread };
                }
                return Finished { retries, spread: Some(summary), ..fin };
            }
            Err(e) => summary.error = Some(e.to_string()),
        }
        Finished { spread: Some(summary), ..fin }
    }

    /// `fin`, or, when it leaves more than h outside the facet valleys (up to
    /// [`MAX_RETRY_EXCESS`] h), its field's rings spaced again for a smaller cusp (see
    /// [`RETRY_AIM`]) when that leaves less.
    fn retried(&self, run: &mut Run, origin: &Origin, fin: Finished) -> Finished {
        let h = run.options.scallop_mm;
        if !fin.exceeds(h) || fin.max_over_h(h) > MAX_RETRY_EXCESS {
            return fin;
        }
        let target = fin.field.target_fraction();
        let retry_target = target * RETRY_AIM / fin.max_over_h(h);
        let mut record = SpacingRetry {
            field: fin.field.name(),
            target_fraction: target,
            max_over_h: fin.max_over_h(h),
            length_mm: fin.summary.length_mm,
            retry_target_fraction: retry_target,
            retry_max_over_h: None,
            retry_length_mm: None,
            error: None,
            kept: false,
        };
        match self.finish(run, origin, fin.field.clone(), retry_target) {
            Ok(retry) => {
                record.retry_max_over_h = Some(retry.max_over_h(h));
                record.retry_length_mm = Some(retry.summary.length_mm);
                record.kept = retry.better_than(&fin, h);
                if record.kept {
                    return Finished { optimise: fin.optimise, retries: vec![record], ..retry };
                }
            }
            Err(e) => record.error = Some(e.to_string()),
        }
        Finished { retries: vec![record], ..fin }
    }
}
