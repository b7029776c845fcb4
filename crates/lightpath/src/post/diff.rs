//! `lightpath diff`: how far two EXRs of one frame are apart, channel by channel — how a
//! farm checks that its merged frame is the single-process render. Cryptomatte layers are
//! compared as what they mean, per pixel each id's coverage, since ids of equal coverage
//! may trade ranks.

use crate::error::PostError;
use crate::output::read_exr;
use crate::post::cryptomatte;
use std::path::Path;

/// The largest difference found between two EXRs.
#[derive(Clone, Debug, PartialEq)]
pub struct Difference {
    /// Channels compared.
    pub channels: usize,
    /// The channel (or Cryptomatte layer) with the largest relative difference, and that
    /// difference: |a − b| / max(|a|, 1) (0 when every value has the same bits; infinite
    /// when a pixel's Cryptomatte ids differ).
    pub worst_channel: String,
    pub worst: f64,
    /// Values whose bits differ (Cryptomatte: pixels whose id → coverage maps differ).
    pub differing_values: u64,
}

/// Compares every channel of `a` and `b`; refuses files with different windows or
/// channel sets.
pub fn diff(a: &Path, b: &Path) -> Result<Difference, PostError> {
    let (x, y) = (read_exr(a)?, read_exr(b)?);
    if (x.frame, x.origin, x.width, x.height) != (y.frame, y.origin, y.width, y.height) {
        return Err(PostError::DifferentPixels {
            first: a.to_path_buf(),
            second: b.to_path_buf(),
            first_window: (x.frame, x.origin, [x.width, x.height]),
            second_window: (y.frame, y.origin, [y.width, y.height]),
        });
    }
    let mut names: Vec<&String> = x.channels.iter().map(|(n, _)| n).collect();
    let mut other: Vec<&String> = y.channels.iter().map(|(n, _)| n).collect();
    names.sort();
    other.sort();
    if names != other {
        return Err(PostError::DifferentChannels {
            first: a.to_path_buf(),
            second: b.to_path_buf(),
        });
    }
    let mut out = Difference {
        channels: names.len(),
        worst_channel: String::new(),
        worst: 0.0,
        differing_values: 0,
    };
    let layers = cryptomatte::layers_in(&x.attributes);
    let mut matte_channels = Vec::new();
    for layer in &layers {
        let groups = names
            .iter()
            .filter(|n| cryptomatte::is_layer_channel(layer, n))
            .count()
            .div_ceil(4);
        let channels = cryptomatte::channel_names(layer, 2 * groups as u32);
        let planes = |e: &crate::output::ExrContents| -> Vec<Vec<f32>> {
            channels
                .iter()
                .map(|c| e.channel(c).map(<[f32]>::to_vec).unwrap_or_default())
                .collect()
        };
        let (p, q) = (planes(&x), planes(&y));
        for px in 0..x.width * x.height {
            let pairs = |planes: &[Vec<f32>]| -> Vec<(u32, f32)> {
                let mut v: Vec<(u32, f32)> = planes
                    .chunks_exact(2)
                    .filter_map(|c| {
                        let (id, cov) = (c[0].get(px)?, c[1].get(px)?);
                        (*cov != 0.0).then_some((id.to_bits(), *cov))
                    })
                    .collect();
                v.sort_by_key(|e| e.0);
                v
            };
            let (a, b) = (pairs(&p), pairs(&q));
            let d = if a.len() != b.len() || a.iter().zip(&b).any(|(s, t)| s.0 != t.0) {
                f64::INFINITY
            } else {
                a.iter()
                    .zip(&b)
                    .map(|(s, t)| (s.1 as f64 - t.1 as f64).abs())
                    .fold(0.0, f64::max)
            };
            if a != b {
                out.differing_values += 1;
            }
            if d > out.worst || (a != b && out.worst_channel.is_empty()) {
                out.worst = out.worst.max(d);
                out.worst_channel = layer.clone();
            }
        }
        matte_channels.extend(channels);
    }
    for (name, values) in &x.channels {
        if matte_channels.contains(name) {
            continue;
        }
        let theirs = y.channel(name).unwrap_or(&[]);
        for (p, q) in values.iter().zip(theirs) {
            if p.to_bits() == q.to_bits() {
                continue;
            }
            out.differing_values += 1;
            let d = if p.is_nan() || q.is_nan() {
                f64::INFINITY
            } else {
                (*p as f64 - *q as f64).abs() / (p.abs() as f64).max(1.0)
            };
            if d > out.worst || out.worst_channel.is_empty() {
                out.worst = out.worst.max(d);
                out.worst_channel = name.clone();
            }
        }
    }
    Ok(out)
}
