//! `lightpath merge`: EXRs of one frame rendered as different sample ranges become one.

use crate::aov::naming::{FIRST_SAMPLE_ATTRIBUTE, INTERRUPTED_ATTRIBUTE, SPP_ATTRIBUTE};
use crate::output::ExrContents;

/// Merges EXRs of one frame rendered as different sample ranges: each channel is the
/// average of the inputs weighted by their sample counts (header `lightpath/spp`).
/// Returns the merged sample count.
pub fn merge(inputs: &[std::path::PathBuf], output: &std::path::Path) -> Result<u64, String> {
    use crate::output::{read_exr, write_channels, ExrOptions};
    if inputs.is_empty() {
        return Err("give the EXRs to merge".into());
    }
    crate::output::target::check_exr_name(output, None)?;
    let input_refs: Vec<&std::path::Path> = inputs.iter().map(|p| p.as_path()).collect();
    crate::output::target::check(output, &input_refs)?;
    let spp_of = |exr: &ExrContents, path: &std::path::Path| -> Result<u64, String> {
        if exr
            .attributes
            .iter()
            .any(|(k, _)| k == INTERRUPTED_ATTRIBUTE)
        {
            return Err(format!(
                "{} is an interrupted render (some rows are empty): finish it with --resume first",
                path.display()
            ));
        }
        exr.attributes
            .iter()
            .find(|(k, _)| k == SPP_ATTRIBUTE)
            .ok_or_else(|| {
                format!(
                    "{} has no {SPP_ATTRIBUTE} header: not a Lightpath render",
                    path.display()
                )
            })
            .and_then(|(_, v)| match v.trim().parse::<u32>() {
                // A render takes 1 ..= 2^32 - 1 samples; 0 would divide by zero.
                Ok(n) if n > 0 => Ok(n as u64),
                _ => Err(format!(
                    "{}: {SPP_ATTRIBUTE} is '{v}': expected a sample count from 1 to {}",
                    path.display(),
                    u32::MAX
                )),
            })
    };
    let first = read_exr(&inputs[0])?;
    let mut total = spp_of(&first, &inputs[0])?;
    let mut names: Vec<String> = first.channels.iter().map(|(n, _)| n.clone()).collect();
    names.sort();
    let mut sums: Vec<(String, Vec<f64>)> = first
        .channels
        .iter()
        .map(|(n, v)| {
            (
                n.clone(),
                v.iter().map(|x| *x as f64 * total as f64).collect(),
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
        these.sort();
        if (exr.width, exr.height) != (first.width, first.height) || these != names {
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
        for (name, sum) in &mut sums {
            let values = exr.channel(name).unwrap_or(&[]);
            for (s, v) in sum.iter_mut().zip(values) {
                *s += *v as f64 * spp as f64;
            }
        }
        total += spp;
    }
    let channels = sums
        .into_iter()
        .map(|(n, s)| {
            (
                n,
                s.into_iter().map(|v| (v / total as f64) as f32).collect(),
            )
        })
        .collect();
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
