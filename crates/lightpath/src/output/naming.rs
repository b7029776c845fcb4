//! Where a render's files go and what its header says about the render: the library's
//! answer, so the binary only passes its arguments through.

use crate::aov::naming::{
    format_ranges, CROP_ATTRIBUTE, FIRST_SAMPLE_ATTRIBUTE, IDENTITY_ATTRIBUTE, INPUTS_ATTRIBUTE,
    SAMPLES_ATTRIBUTE, SCENE_ATTRIBUTE,
};
use crate::film::PixelWindow;
use crate::identity::Identity;
use std::path::{Path, PathBuf};

/// The files one render writes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OutputPaths {
    pub exr: PathBuf,
    pub png: PathBuf,
}

/// `output` if given, else `<scene file stem>.exr` in the working directory; the PNG
/// preview always sits beside the EXR.
pub fn output_paths(scene: &str, output: Option<&Path>) -> OutputPaths {
    let exr = match output {
        Some(p) => p.to_path_buf(),
        None => PathBuf::from(
            Path::new(scene)
                .file_stem()
                .map(|s| s.to_os_string())
                .unwrap_or_else(|| "render".into()),
        )
        .with_extension("exr"),
    };
    OutputPaths {
        png: preview_path(&exr),
        exr,
    }
}

/// The PNG preview beside a render's EXR: the EXR's name with `.png` for its last
/// extension, so frame numbers stay (`shot.0001.exr` → `shot.0001.png`; two frames once
/// wrote the same `shot.png`).
pub fn preview_path(exr: &Path) -> PathBuf {
    exr.with_extension("png")
}

/// Where an interrupted render writes its rows done: beside the output, as
/// `<stem>.partial.exr` and `<stem>.partial.png`, so a finished image under the output's
/// own name is never replaced by an unfinished one.
pub fn partial_paths(paths: &OutputPaths) -> OutputPaths {
    let exr = paths.exr.with_extension("partial.exr");
    OutputPaths {
        png: preview_path(&exr),
        exr,
    }
}

/// What a render's header records about which part of a frame it is (its settings,
/// `spp` and `seed` included, are [`settings_attributes`]').
#[derive(Clone, Debug)]
pub struct RenderMetadata {
    pub scene: String,
    pub spp: u32,
    pub first_sample: u32,
}

impl RenderMetadata {
    /// The header attributes (`lightpath/scene`, `first_sample`, and the sample range).
    pub fn attributes(&self) -> Vec<(String, String)> {
        let first = self.first_sample as u64;
        vec![
            (SCENE_ATTRIBUTE.to_string(), self.scene.clone()),
            (
                FIRST_SAMPLE_ATTRIBUTE.to_string(),
                self.first_sample.to_string(),
            ),
            (
                SAMPLES_ATTRIBUTE.to_string(),
                format_ranges(&[(first, first + self.spp as u64)]),
            ),
        ]
    }
}

/// Every render setting (`settings.rs`: `lightpath/spp`, `lightpath/seed` and
/// `lightpath/setting/<name>`), the render's identity (`identity.rs`: its hash and its
/// manifest of inputs), and the crop.
pub fn settings_attributes(
    scene: &crate::scene::Scene,
    identity: &Identity,
    crop: PixelWindow,
) -> Vec<(String, String)> {
    let mut out = crate::settings::header_attributes(&scene.settings);
    // The camera is part of the identity but no render setting.
    out.extend(
        identity
            .settings
            .iter()
            .filter(|(k, _)| k == "camera")
            .map(|(k, v)| (crate::identity::setting_attribute(k), v.clone())),
    );
    out.push((IDENTITY_ATTRIBUTE.into(), identity.hash_text()));
    out.push((INPUTS_ATTRIBUTE.into(), identity.manifest()));
    out.push((CROP_ATTRIBUTE.into(), crop.to_string()));
    out
}

/// A UTC date as `capDate` writes it (`YYYY:MM:DD hh:mm:ss`), from seconds since 1970.
pub fn capture_date(unix_seconds: u64) -> String {
    let days = (unix_seconds / 86_400) as i64;
    let rem = unix_seconds % 86_400;
    // Howard Hinnant's civil_from_days.
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + (m <= 2) as i64;
    format!(
        "{y:04}:{m:02}:{d:02} {:02}:{:02}:{:02}",
        rem / 3600,
        rem / 60 % 60,
        rem % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_output_is_the_scene_stem_with_the_png_beside_it() {
        let p = output_paths("scenes/cornell.toml", None);
        assert_eq!(p.exr, PathBuf::from("cornell.exr"));
        assert_eq!(p.png, PathBuf::from("cornell.png"));
        let p = output_paths("x.toml", Some(Path::new("out/shot.0001.exr")));
        assert_eq!(p.png, PathBuf::from("out/shot.0001.png"));
        let partial = partial_paths(&p);
        assert_eq!(partial.exr, PathBuf::from("out/shot.0001.partial.exr"));
        assert_eq!(partial.png, PathBuf::from("out/shot.0001.partial.png"));
    }

    #[test]
    fn capture_dates_are_utc_calendar_dates() {
        assert_eq!(capture_date(0), "1970:01:01 00:00:00");
        assert_eq!(capture_date(951_782_400), "2000:02:29 00:00:00");
        assert_eq!(capture_date(1_798_761_599), "2026:12:31 23:59:59");
    }
}
