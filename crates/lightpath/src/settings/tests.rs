use super::*;
use crate::scene::Source;

/// One setting's example values, as a flag and as TOML writes them.
struct Example {
    key: &'static str,
    valid: (&'static str, &'static str),
    /// Out of its range (or, for a setting any value of its type suits, not of its type).
    invalid: (&'static str, &'static str),
}

const fn ex(
    key: &'static str,
    valid: (&'static str, &'static str),
    invalid: (&'static str, &'static str),
) -> Example {
    Example {
        key,
        valid,
        invalid,
    }
}

/// An example for every setting; `every_setting_has_an_example` keeps it complete.
const EXAMPLES: &[Example] = &[
    ex("spp", ("64", "64"), ("0", "0")),
    ex("max_depth", ("3", "3"), ("0", "0")),
    ex("max_diffuse_depth", ("2", "2"), ("-1", "-1")),
    ex("max_specular_depth", ("0", "0"), ("1.5", "1.5")),
    ex("rr_depth", ("2", "2"), ("-3", "-3")),
    ex("clamp_direct", ("2.5", "2.5"), ("-1", "-1")),
    ex("clamp_indirect", ("10", "10"), ("-0.5", "-0.5")),
    ex("seed", ("7", "7"), ("-7", "-7")),
    ex(
        "sampler",
        ("independent", "\"independent\""),
        ("halton", "\"halton\""),
    ),
    ex(
        "light_selection",
        ("uniform", "\"uniform\""),
        ("random", "\"random\""),
    ),
    ex("light_candidates", ("4", "4"), ("65", "65")),
    ex("light_samples", ("3", "3"), ("0", "0")),
    ex(
        "volume_sampling",
        ("distance", "\"distance\""),
        ("equiangular", "\"equiangular\""),
    ),
    ex("noise_threshold", ("0.1", "0.1"), ("-1", "-1")),
    ex("min_spp", ("8", "8"), ("0", "0")),
    ex("regularize", ("0.3", "0.3"), ("5", "5")),
    ex("guiding", ("on", "\"on\""), ("yes", "\"yes\"")),
    ex("guiding_passes", ("5", "5"), ("13", "13")),
    ex("light_connections", ("on", "\"on\""), ("both", "\"both\"")),
    ex("glint_sampling", ("off", "\"off\""), ("yes", "\"yes\"")),
    ex("frame", ("12.5", "12.5"), ("1e12", "1e12")),
    ex(
        "render_settings",
        ("/Render/Settings", "\"/Render/Settings\""),
        ("Settings", "\"Settings\""),
    ),
    ex("resolution", ("64x32", "[64, 32]"), ("0x32", "[0, 32]")),
    ex(
        "filter",
        ("blackman-harris", "\"blackman-harris\""),
        ("tent", "\"tent\""),
    ),
    ex("filter_stddev", ("0.7", "0.7"), ("0", "0")),
    ex("filter_width", ("2", "2"), ("-1", "-1")),
];

fn setting(key: &str) -> &'static Setting {
    SETTINGS.iter().find(|s| s.key == key).unwrap()
}

/// A scene file with one setting written.
fn toml_with(s: &Setting, value: &str) -> Result<RenderDesc, String> {
    let text = format!("[{}]\n{} = {value}\n", s.section.name(), s.key);
    parse("settings.toml", &text)
        .map(|d| d.render)
        .map_err(|e| {
            assert_eq!((e.line, e.file.as_str()), (2, "settings.toml"), "{e}");
            e.message
        })
}

fn parse(name: &str, text: &str) -> Result<crate::scene::desc::SceneDesc, crate::SceneError> {
    Source {
        name: name.into(),
        text: text.into(),
        dir: ".".into(),
    }
    .parse()
}

/// The settings after one flag.
fn flag_with(s: &Setting, text: &str) -> Result<RenderDesc, String> {
    let mut overrides = SettingOverrides::default();
    (s.read_flag)(text, &mut overrides)?;
    let mut render = RenderDesc::default();
    overrides.apply(&mut render);
    Ok(render)
}

#[test]
fn every_setting_has_an_example() {
    let keys: Vec<&str> = SETTINGS.iter().map(|s| s.key).collect();
    let examples: Vec<&str> = EXAMPLES.iter().map(|e| e.key).collect();
    assert_eq!(keys, examples);
}

#[test]
fn every_setting_reads_the_same_from_a_flag_and_from_toml() {
    for e in EXAMPLES {
        let s = setting(e.key);
        let default = (s.show)(&RenderDesc::default());
        // A valid value: the same settings both ways, and not the default.
        let from_flag = flag_with(s, e.valid.0).unwrap();
        let from_toml = toml_with(s, e.valid.1).unwrap();
        assert_eq!(from_flag, from_toml, "{}", e.key);
        assert_ne!(
            (s.show)(&from_flag),
            default,
            "{}: an example, not the default",
            e.key
        );
        assert_eq!(check(&from_flag), Ok(()), "{}", e.key);
        // An invalid one: refused both ways, with the same message naming the setting.
        let flag_error = flag_with(s, e.invalid.0).unwrap_err();
        let toml_error = toml_with(s, e.invalid.1).unwrap_err();
        assert_eq!(flag_error, toml_error, "{}", e.key);
        assert!(flag_error.contains(e.key), "{flag_error}");
    }
}

#[test]
fn unwritten_settings_are_the_defaults_both_ways() {
    let empty = parse("empty.toml", "").unwrap().render;
    let mut overridden = RenderDesc::default();
    SettingOverrides::default().apply(&mut overridden);
    for s in SETTINGS {
        let default = (s.show)(&RenderDesc::default());
        assert_eq!((s.show)(&empty), default, "{}", s.key);
        assert_eq!((s.show)(&overridden), default, "{}", s.key);
    }
}

#[test]
fn ranges_refuse_what_the_issue_named() {
    assert_eq!(
        flag_with(setting("regularize"), "5").unwrap_err(),
        "regularize must be between 0 and 1, got 5"
    );
    assert_eq!(
        flag_with(setting("noise_threshold"), "-1").unwrap_err(),
        "noise_threshold must be between 0 and 1000000, got -1"
    );
    assert_eq!(
        flag_with(setting("max_depth"), "0").unwrap_err(),
        "max_depth must be at least 1, got 0"
    );
    assert_eq!(
        flag_with(setting("clamp_direct"), "nan").unwrap_err(),
        "clamp_direct must be a finite number, got NaN"
    );
    assert_eq!(
        flag_with(setting("clamp_indirect"), "inf").unwrap_err(),
        "clamp_indirect must be a finite number, got inf"
    );
    assert_eq!(
        flag_with(setting("spp"), "many").unwrap_err(),
        "spp must be a whole number at least 1, got 'many'"
    );
    assert_eq!(
        flag_with(setting("sampler"), "halton").unwrap_err(),
        "unknown sampler 'halton': expected sobol or independent"
    );
    assert_eq!(
        flag_with(setting("sampler"), "sobl").unwrap_err(),
        "unknown sampler 'sobl': expected sobol or independent (did you mean 'sobol'?)"
    );
}

#[test]
fn min_spp_above_spp_is_refused_and_its_default_never_is() {
    let mut render = RenderDesc {
        spp: 16,
        min_spp: Some(32),
        ..RenderDesc::default()
    };
    let e = check(&render).unwrap_err();
    assert_eq!(
        e,
        crate::error::SettingError::MinSppAboveSpp {
            min_spp: 32,
            spp: 16
        }
    );
    assert!(
        e.to_string().starts_with("min_spp (32) is above spp (16)"),
        "{e}"
    );
    render.min_spp = Some(16);
    assert_eq!(check(&render), Ok(()));
    // The default pilot is 16 samples, or spp if fewer.
    render.min_spp = None;
    render.spp = 4;
    assert_eq!(check(&render), Ok(()));
    let e = parse("pilot.toml", "[render]\nspp = 8\nmin_spp = 9\n").unwrap_err();
    assert!(e.message.starts_with("min_spp (9) is above spp (8)"), "{e}");
}

#[test]
fn the_header_keeps_its_attribute_names_and_values() {
    let mut render = RenderDesc::default();
    let attributes = |r: &RenderDesc| -> Vec<(String, String)> {
        let mut a = header_attributes(r);
        a.sort();
        a
    };
    let expected = [
        ("lightpath/seed", "0"),
        ("lightpath/setting/clamp_direct", "0"),
        ("lightpath/setting/clamp_indirect", "0"),
        ("lightpath/setting/filter", "box"),
        ("lightpath/setting/frame", "none"),
        ("lightpath/setting/glint_sampling", "on"),
        ("lightpath/setting/guiding", "auto"),
        ("lightpath/setting/guiding_passes", "4"),
        ("lightpath/setting/light_candidates", "1"),
        ("lightpath/setting/light_connections", "off"),
        ("lightpath/setting/light_samples", "1"),
        ("lightpath/setting/light_selection", "tree"),
        ("lightpath/setting/max_depth", "8"),
        ("lightpath/setting/max_diffuse_depth", "none"),
        ("lightpath/setting/max_specular_depth", "none"),
        ("lightpath/setting/min_spp", "16"),
        ("lightpath/setting/noise_threshold", "0"),
        ("lightpath/setting/regularize", "0"),
        ("lightpath/setting/render_settings", "none"),
        ("lightpath/setting/resolution", "256x256"),
        ("lightpath/setting/rr_depth", "5"),
        ("lightpath/setting/sampler", "sobol"),
        ("lightpath/setting/volume_sampling", "mis"),
        ("lightpath/spp", "16"),
    ];
    let owned = |list: &[(&str, &str)]| -> Vec<(String, String)> {
        list.iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    };
    assert_eq!(attributes(&render), owned(&expected));
    render.filter = FilterKind::Gaussian;
    render.filter_stddev = 0.75;
    render.max_diffuse_depth = Some(3);
    render.clamp_indirect = 10.0;
    render.noise_threshold = 0.05;
    let a = attributes(&render);
    for (k, v) in [
        ("lightpath/setting/filter", "gaussian 0.75"),
        ("lightpath/setting/max_diffuse_depth", "3"),
        ("lightpath/setting/clamp_indirect", "10"),
        ("lightpath/setting/noise_threshold", "0.05"),
    ] {
        assert!(a.contains(&(k.to_string(), v.to_string())), "{k}: {a:?}");
    }
}

#[test]
fn identity_holds_what_changes_the_converged_image_and_not_the_parts_split() {
    let keys: Vec<&str> = identity_pairs(&RenderDesc::default())
        .into_iter()
        .map(|(k, _)| k)
        .collect();
    for key in [
        "max_depth",
        "clamp_direct",
        "regularize",
        "resolution",
        "filter",
    ] {
        assert!(keys.contains(&key), "{key}");
    }
    for key in ["spp", "seed", "sampler", "min_spp"] {
        assert!(!keys.contains(&key), "{key}");
    }
    let deeper = RenderDesc {
        max_depth: 3,
        ..RenderDesc::default()
    };
    assert_ne!(
        identity_pairs(&deeper),
        identity_pairs(&RenderDesc::default())
    );
    let more_samples = RenderDesc {
        spp: 1024,
        ..RenderDesc::default()
    };
    assert_eq!(
        identity_pairs(&more_samples),
        identity_pairs(&RenderDesc::default())
    );
    assert_eq!(
        per_part_attributes().collect::<Vec<_>>(),
        vec![SPP_ATTRIBUTE.to_string()]
    );
}

#[test]
fn unknown_keys_name_the_section_and_its_keys() {
    let e = parse("typo.toml", "[render]\nmax_deph = 3\n").unwrap_err();
    assert_eq!(e.line, 2);
    assert!(
        e.message
            .starts_with("unknown key 'max_deph' in [render]: expected one of spp, max_depth,"),
        "{e}"
    );
    assert!(e.message.ends_with(" (did you mean 'max_depth'?)"), "{e}");
}

#[test]
fn every_setting_is_documented() {
    let doc = include_str!("../../../../docs/scene-format.md");
    for s in SETTINGS {
        assert!(
            doc.contains(&format!("{} = ", s.key)),
            "[{}] {}",
            s.section.name(),
            s.key
        );
    }
}
