//! What a render checks before it starts: settings that cannot be honoured, requests
//! above the `limits`, outputs that could not be written (or would overwrite the scene),
//! and what deserves a warning. A failure here costs nothing; the same failure after an
//! hour's render cost the hour.

use crate::error::{Error, OutputError, SettingError};
use crate::film::Film;
use crate::integrator::connect::LightConnections;
use crate::limits::Limits;
use crate::output::naming::OutputPaths;
use crate::output::target;
use crate::scene::desc::SceneDesc;
use crate::scene::Scene;
use std::collections::BTreeSet;
use std::path::Path;

/// The settings (`settings.rs`), the sample range and the film size, as the scene and
/// the overrides set them.
pub fn settings(desc: &SceneDesc, first_sample: u32) -> Result<(), SettingError> {
    crate::settings::check(&desc.render)?;
    let spp = desc.render.spp;
    if first_sample.checked_add(spp).is_none() {
        return Err(SettingError::PastLastSample { first_sample, spp });
    }
    let [w, h] = desc.render.resolution;
    let pixels = w as u64 * h as u64;
    let limits = Limits::current();
    limits.check_pixels(pixels, &format!("a {w}x{h} film"))?;
    limits.check_samples(pixels * spp as u64, &format!("{w}x{h} pixels at {spp} spp"))?;
    Ok(())
}

/// The film's memory and the AOVs' channel names, once the AOVs are known.
pub fn film(scene: &Scene) -> Result<(), Error> {
    let (w, h) = (scene.camera.width as u64, scene.camera.height as u64);
    let stride = Film::stride_with(scene.aovs.len(), scene.variance_aovs.len()) as u64;
    // The film's planes and the EXR encoder's blocks in flight: the peak is 1.04× the
    // film with `zips`, 1.33× with `piz` (docs/performance.md), so 1.5× with a margin.
    let mut bytes = w * h * stride * 4 * 3 / 2;
    if scene.settings.noise_threshold > 0.0 {
        // Adaptive sampling: the pilot's moments (2 f64), counts, predictions, targets
        // and the max filter's rows (u32 each) per pixel.
        bytes += w * h * (16 + 4 * 4);
    }
    if scene.settings.light_connections == LightConnections::On
        && crate::integrator::connect::traces_to_camera(scene)
    {
        // Light tracing's splat sums: an i64 per channel of each AOV and of each
        // variance's squares (film/splats.rs).
        bytes += w * h * (scene.aovs.len() + scene.variance_aovs.len()) as u64 * 3 * 8;
    }
    Limits::current().check_memory(
        bytes,
        &format!("a {w}x{h} film with {} AOVs", scene.aovs.len()),
    )?;
    let mut seen = BTreeSet::new();
    for aov in &scene.aovs {
        if !seen.insert(aov.name.as_str()) {
            return Err(Error::Plan(format!(
                "two AOVs are named '{}' (an AOV of the scene or --aov and a light-group \
                 part?): each EXR channel name must be unique",
                aov.name
            )));
        }
    }
    Ok(())
}

/// The EXR and its preview (and an interrupted render's partial pair) can be written
/// where asked, without destroying the scene or any file it reads.
pub fn outputs(paths: &OutputPaths, inputs: &[&Path]) -> Result<(), OutputError> {
    target::check_exr_name(&paths.exr, Some(&paths.png))?;
    let partial = crate::output::naming::partial_paths(paths);
    for path in [&paths.exr, &paths.png, &partial.exr, &partial.png] {
        target::check(path, inputs)?;
    }
    Ok(())
}

/// Things worth a word before rendering: an LPE label that no object or light carries
/// (a scene without light is `scene::load::defaults::no_light_warning`'s).
pub fn scene_warnings(scene: &Scene) -> Vec<String> {
    let mut out = Vec::new();
    let mut labels: BTreeSet<&str> = BTreeSet::new();
    for o in &scene.objects {
        labels.extend(o.groups.iter().map(String::as_str));
    }
    for l in &scene.lights {
        labels.extend(l.groups.iter().map(String::as_str));
    }
    for aov in &scene.aovs {
        if aov.part_of.is_some() {
            continue;
        }
        // The definition as written: a standard name's own labels ('passthru') are not
        // the scene's to provide.
        for label in quoted_labels(&aov.definition) {
            if !labels.contains(label) {
                out.push(format!(
                    "AOV '{}' ({}): no object or light has the label '{label}'{}, so that \
                     part of the expression never matches",
                    aov.name,
                    aov.definition,
                    crate::suggest::did_you_mean(label, labels.iter().copied())
                ));
            }
        }
    }
    out
}

/// The `'labels'` an expression names, in order, each once.
fn quoted_labels(expression: &str) -> Vec<&str> {
    let mut out: Vec<&str> = Vec::new();
    let mut rest = expression;
    while let Some(open) = rest.find('\'') {
        let after = &rest[open + 1..];
        let Some(close) = after.find('\'') else { break };
        let label = &after[..close];
        if !out.contains(&label) {
            out.push(label);
        }
        rest = &after[close + 1..];
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_are_read_from_the_quotes() {
        assert_eq!(
            quoted_labels("C<.>*[<L.'key'>O]|<L'fill'>'key'"),
            vec!["key", "fill"]
        );
        assert!(quoted_labels("C<RD>[<L.>O]").is_empty());
    }
}
