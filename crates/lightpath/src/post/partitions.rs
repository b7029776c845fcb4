//! The partition checks of `lightpath aovs`: which AOVs an EXR says sum to which, read
//! from its structured header attributes, and how far they are from summing.

use crate::aov::naming::{self, PartitionKind};
use crate::output::ExrContents;
use crate::post::comp::{aov_planes, evaluate, Term};
use glam::Vec3A;
use std::fmt::Write;
use std::path::Path;

/// The largest relative error of a partition that `lightpath aovs` (and the viewer) call
/// fine by default: float sums of a few dozen parts stay well below it.
pub const DEFAULT_TOLERANCE: f32 = 1e-4;

/// `lightpath aovs`: an EXR's AOVs with their expressions and each declared partition's
/// check, as the text to print; `Ok(false)` when a partition is off by more than
/// `tolerance`.
pub fn report(path: &Path, tolerance: f32) -> Result<(String, bool), crate::error::ExrReadError> {
    let exr = crate::output::read_exr(path)?;
    let mut aovs = exr.aovs();
    aovs.sort();
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{}: {}x{}, {} AOVs",
        path.display(),
        exr.width,
        exr.height,
        aovs.len()
    );
    for (name, def) in &aovs {
        let _ = writeln!(out, "  {name:<24} {def}");
    }
    let mut ok = true;
    for (name, values) in &exr.channels {
        let bad = values.iter().filter(|v| !v.is_finite()).count();
        if bad > 0 {
            ok = false;
            let _ = writeln!(out, "FAIL channel {name}: {bad} NaN or infinite values");
        }
    }
    let checks = check_partitions(&exr);
    if checks.is_empty() {
        out.push_str("no known partitions (standard set, light groups, bounces) to check\n");
    }
    for c in &checks {
        let pass = c.max_relative_error <= tolerance;
        ok &= pass;
        let _ = writeln!(
            out,
            "{} {} = {}: max relative error {:.2e}",
            if pass { "ok  " } else { "FAIL" },
            c.whole,
            c.parts.join(" + "),
            c.max_relative_error
        );
    }
    Ok((out, ok))
}

/// A partition of an AOV that the EXR holds, and how far its parts are from summing to it.
#[derive(Clone, Debug)]
pub struct PartitionCheck {
    pub whole: String,
    pub parts: Vec<String>,
    /// max over pixels and channels of |Σ parts − whole| / max(|whole|, 1e-3).
    pub max_relative_error: f32,
}

/// Finds the partitions an EXR's header declares (the standard set, light-group splits,
/// bounce AOVs) and measures each.
pub fn check_partitions(exr: &ExrContents) -> Vec<PartitionCheck> {
    // One candidate per (whole, partition kind), parts in their natural order.
    let mut parts = naming::parts_from_attributes(&exr.attributes);
    parts.sort_by_key(|p| (p.whole.clone(), p.kind, naming::part_order(p)));
    let mut candidates: Vec<(String, Vec<String>)> = Vec::new();
    let mut last: Option<(String, PartitionKind)> = None;
    for p in parts {
        let key = Some((p.whole.clone(), p.kind));
        match candidates.last_mut() {
            Some((_, names)) if key == last => names.push(p.name),
            _ => candidates.push((p.whole.clone(), vec![p.name])),
        }
        last = key;
    }
    candidates
        .into_iter()
        .filter_map(|(whole, parts)| {
            let w = aov_planes(exr, &whole).ok()?;
            let terms: Vec<Term> = parts
                .iter()
                .map(|p| Term {
                    scale: Vec3A::ONE,
                    aov: p.clone(),
                })
                .collect();
            let sum = evaluate(exr, &terms).ok()?;
            let mut worst = 0.0f32;
            for c in 0..3 {
                for (s, v) in sum[c].iter().zip(w[c]) {
                    let error = (s - v).abs() / v.abs().max(1e-3);
                    // `max` ignores NaN: a NaN pixel must fail the check, not pass it.
                    worst = if error.is_nan() {
                        f32::INFINITY
                    } else {
                        worst.max(error)
                    };
                }
            }
            Some(PartitionCheck {
                whole,
                parts,
                max_relative_error: worst,
            })
        })
        .collect()
}
