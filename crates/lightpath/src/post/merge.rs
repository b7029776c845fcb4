//! `lightpath merge`: EXRs of one frame rendered as different sample ranges become one.

use crate::aov::naming::{FIRST_SAMPLE_ATTRIBUTE, SAMPLE_COUNT, SPP_ATTRIBUTE};
use crate::output::ExrContents;

/// Merges EXRs of one frame rendered as different sample ranges: each channel is the
/// average of the inputs weighted by their sample counts, per pixel: the `sampleCount`
/// channel where adaptive sampling wrote one, else the header's `lightpath/spp`. The
/// merged file has a `sampleCount` channel (the sums) when any input had one.
/// Returns the merged sample count (at most, per pixel).
pub fn merge(inputs: &[std::path::PathBuf], output: &std::path::Path) -> Result<u64, String> {
    use crate::output::{read_exr, write_channels, ExrOptions};
    if inputs.is_empty() {
        return Err("give the EXRs to merge".into());
    }
    let spp_of = |exr: &ExrContents, path: &std::path::Path| -> Result<u64, String> {
        exr.attributes
            .iter()
            .find(|(k, _)| k == SPP_ATTRIBUTE)
            .and_then(|(_, v)| v.parse().ok())
            .ok_or_else(|| {
                format!(
                    "{} has no {SPP_ATTRIBUTE} header: not a Lightpath render",
                    path.display()
                )
            })
    };
    let first = read_exr(&inputs[0])?;
    let pixels = first.width * first.height;
    // Per pixel: the samples an input took there.
    let counts_of = |exr: &ExrContents, spp: u64| -> Vec<f64> {
        match exr.channel(SAMPLE_COUNT) {
            Some(c) => c.iter().map(|&n| n as f64).collect(),
            None => vec![spp as f64; pixels],
        }
    };
    let mut total = spp_of(&first, &inputs[0])?;
    let mut any_counts = first.channel(SAMPLE_COUNT).is_some();
    let mut weights = counts_of(&first, total);
    let mut names: Vec<String> = first.channels.iter().map(|(n, _)| n.clone()).collect();
    names.sort();
    let mut sums: Vec<(String, Vec<f64>)> = first
        .channels
        .iter()
        .filter(|(n, _)| n != SAMPLE_COUNT)
        .map(|(n, v)| {
            (
                n.clone(),
                v.iter().zip(&weights).map(|(x, w)| *x as f64 * w).collect(),
            )
        })
        .collect();
    let mut ranges = vec![first
        .attributes
        .iter()
        .find(|(k, _)| k == FIRST_SAMPLE_ATTRIBUTE)
        .map(|(_, v)| v.clone())];
    for path in &inputs[1..] {
        let exr = read_exr(path)?;
        let spp = spp_of(&exr, path)?;
        let mut these: Vec<String> = exr.channels.iter().map(|(n, _)| n.clone()).collect();
        these.retain(|n| n != SAMPLE_COUNT);
        these.sort();
        let mut expected = names.clone();
        expected.retain(|n| n != SAMPLE_COUNT);
        if (exr.width, exr.height) != (first.width, first.height) || these != expected {
            return Err(format!(
                "{} is not the same frame: its size or channels differ from {}",
                path.display(),
                inputs[0].display()
            ));
        }
        let range = exr
            .attributes
            .iter()
            .find(|(k, _)| k == FIRST_SAMPLE_ATTRIBUTE)
            .map(|(_, v)| v.clone());
        if range.is_some() && ranges.contains(&range) {
            return Err(format!(
                "{} repeats sample range {}: its samples would count twice",
                path.display(),
                range.unwrap_or_default()
            ));
        }
        ranges.push(range);
        any_counts |= exr.channel(SAMPLE_COUNT).is_some();
        let counts = counts_of(&exr, spp);
        for (name, sum) in &mut sums {
            let values = exr.channel(name).unwrap_or(&[]);
            for ((s, v), n) in sum.iter_mut().zip(values).zip(&counts) {
                *s += *v as f64 * n;
            }
        }
        for (w, n) in weights.iter_mut().zip(&counts) {
            *w += n;
        }
        total += spp;
    }
    let mut channels: Vec<(String, Vec<f32>)> = sums
        .into_iter()
        .map(|(n, s)| {
            let means = s
                .into_iter()
                .zip(&weights)
                .map(|(v, w)| if *w > 0.0 { (v / w) as f32 } else { 0.0 })
                .collect();
            (n, means)
        })
        .collect();
    if any_counts {
        channels.push((
            SAMPLE_COUNT.into(),
            weights.iter().map(|&w| w as f32).collect(),
        ));
    }
    let mut attributes: Vec<(String, String)> = first
        .attributes
        .iter()
        .filter(|(k, _)| k != SPP_ATTRIBUTE && k != FIRST_SAMPLE_ATTRIBUTE)
        .cloned()
        .collect();
    attributes.push((SPP_ATTRIBUTE.into(), total.to_string()));
    write_channels(
        output,
        first.width,
        first.height,
        channels,
        &attributes,
        ExrOptions::default(),
    )?;
    Ok(total)
}
