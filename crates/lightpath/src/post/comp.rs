//! Additive compositing from an EXR's AOVs (`lightpath comp`): relighting by addition
//! and subtraction, never a re-render.

use crate::aov::naming::{self, channel_names};
use crate::error::PostError;
use crate::output::{read_exr, write_image, write_png_rgb, ExrContents};
use glam::Vec3A;
use std::path::PathBuf;

/// One term of a compositing expression: `scale * aov`.
#[derive(Clone, Debug, PartialEq)]
pub struct Term {
    pub scale: Vec3A,
    pub aov: String,
}

/// Parses `beauty + 0.5*beauty_key - indirectSpecular + (1,0.4,0.4)*caustics`.
pub fn parse(expr: &str) -> Result<Vec<Term>, PostError> {
    let mut p = Cursor {
        s: expr.as_bytes(),
        i: 0,
    };
    terms(&mut p).map_err(|(at, expected)| PostError::Expression {
        expression: expr.to_string(),
        at,
        expected,
    })
}

/// Where a parse failed (a byte offset) and what was expected there.
type Expected = (usize, &'static str);

fn terms(p: &mut Cursor) -> Result<Vec<Term>, Expected> {
    let mut terms = Vec::new();
    let mut sign = 1.0;
    p.ws();
    if p.eat(b'-') {
        sign = -1.0;
    } else {
        p.eat(b'+');
    }
    loop {
        p.ws();
        let mut scale = Vec3A::ONE;
        if p.peek()
            .is_some_and(|c| c.is_ascii_digit() || c == b'.' || c == b'(')
        {
            scale = p.factor()?;
            p.ws();
            if !p.eat(b'*') {
                return Err(p.error("'*' after the factor"));
            }
            p.ws();
        }
        let aov = p.name()?;
        p.ws();
        // A factor may also follow the name: `key*2`.
        if p.eat(b'*') {
            p.ws();
            scale *= p.factor()?;
            p.ws();
        }
        terms.push(Term {
            scale: scale * sign,
            aov,
        });
        match p.peek() {
            None => break,
            Some(b'+') => sign = 1.0,
            Some(b'-') => sign = -1.0,
            Some(_) => return Err(p.error("'+', '-' or the end")),
        }
        p.i += 1;
    }
    Ok(terms)
}

struct Cursor<'a> {
    s: &'a [u8],
    i: usize,
}

impl Cursor<'_> {
    fn peek(&self) -> Option<u8> {
        self.s.get(self.i).copied()
    }
    fn ws(&mut self) {
        while self.peek().is_some_and(|c| c.is_ascii_whitespace()) {
            self.i += 1;
        }
    }
    fn eat(&mut self, c: u8) -> bool {
        if self.peek() == Some(c) {
            self.i += 1;
            true
        } else {
            false
        }
    }
    fn error(&self, expected: &'static str) -> Expected {
        (self.i, expected)
    }
    fn number(&mut self) -> Result<f32, Expected> {
        let start = self.i;
        while self
            .peek()
            .is_some_and(|c| c.is_ascii_digit() || matches!(c, b'.' | b'e' | b'E' | b'-' | b'+'))
        {
            // A sign is part of the number only right after an exponent or at its start.
            let c = self.s[self.i];
            if matches!(c, b'-' | b'+')
                && self.i > start
                && !matches!(self.s[self.i - 1], b'e' | b'E')
            {
                break;
            }
            self.i += 1;
        }
        std::str::from_utf8(&self.s[start..self.i])
            .ok()
            .and_then(|t| t.parse::<f32>().ok())
            .ok_or_else(|| self.error("a number"))
    }
    fn factor(&mut self) -> Result<Vec3A, Expected> {
        if self.eat(b'(') {
            let mut v = [0.0; 3];
            for (k, slot) in v.iter_mut().enumerate() {
                self.ws();
                *slot = self.number()?;
                self.ws();
                if k < 2 && !self.eat(b',') {
                    return Err(self.error("',' in an (r,g,b) factor"));
                }
            }
            if !self.eat(b')') {
                return Err(self.error("')' closing the (r,g,b) factor"));
            }
            Ok(Vec3A::from(v))
        } else {
            Ok(Vec3A::splat(self.number()?))
        }
    }
    fn name(&mut self) -> Result<String, Expected> {
        let start = self.i;
        while self
            .peek()
            .is_some_and(|c| c.is_ascii_alphanumeric() || c == b'_')
        {
            self.i += 1;
        }
        if self.i == start || self.s[start].is_ascii_digit() {
            return Err(self.error("an AOV name"));
        }
        Ok(String::from_utf8_lossy(&self.s[start..self.i]).into_owned())
    }
}

/// The RGB planes of an AOV in an EXR.
pub fn aov_planes<'a>(exr: &'a ExrContents, aov: &str) -> Result<[&'a [f32]; 3], PostError> {
    let names = channel_names(aov);
    let mut out: [&[f32]; 3] = [&[], &[], &[]];
    for (slot, name) in out.iter_mut().zip(&names) {
        *slot = exr.channel(name).ok_or_else(|| {
            let mut known: Vec<String> = exr.aovs().into_iter().map(|(n, _)| n).collect();
            known.sort();
            PostError::NoAov {
                aov: aov.to_string(),
                channel: name.clone(),
                suggestion: crate::suggest::did_you_mean(aov, known.iter().map(String::as_str)),
                known,
            }
        })?;
    }
    Ok(out)
}

/// Evaluates a sum of scaled AOVs, pixel by pixel.
pub fn evaluate(exr: &ExrContents, terms: &[Term]) -> Result<[Vec<f32>; 3], PostError> {
    let n = exr.width * exr.height;
    let mut out = [vec![0.0f32; n], vec![0.0f32; n], vec![0.0f32; n]];
    for t in terms {
        let planes = aov_planes(exr, &t.aov)?;
        for c in 0..3 {
            let s = t.scale[c];
            for (o, v) in out[c].iter_mut().zip(planes[c]) {
                *o += s * v;
            }
        }
    }
    Ok(out)
}

/// Terms that rebalance light groups of a split AOV: `base + Σ (gain − 1) · base_group`.
/// The part of each group is looked up in the header's structured partition attributes
/// (`lightpath/part/…`, `lightpath/lightgroup/…`), never in the definitions' prose.
pub fn gain_terms(
    exr: &ExrContents,
    base: &str,
    gains: &[(String, Vec3A)],
) -> Result<Vec<Term>, PostError> {
    let parts: Vec<naming::PartOf> = naming::parts_from_attributes(&exr.attributes)
        .into_iter()
        .filter(|p| p.whole == base && p.kind == naming::PartitionKind::LightGroups)
        .collect();
    let mut terms = vec![Term {
        scale: Vec3A::ONE,
        aov: base.to_string(),
    }];
    for (group, gain) in gains {
        let wanted = (!naming::is_default_group(group)).then_some(group.as_str());
        let part = parts
            .iter()
            .find(|p| p.group.as_ref().map(|g| g.as_deref()) == Some(wanted))
            .ok_or_else(|| {
                let mut known: Vec<String> = parts
                    .iter()
                    .map(|p| match &p.group {
                        Some(Some(g)) => g.clone(),
                        _ => naming::DEFAULT_GROUP.to_string(),
                    })
                    .collect();
                known.sort();
                PostError::NoLightGroup {
                    base: base.to_string(),
                    group: group.clone(),
                    suggestion: crate::suggest::did_you_mean(
                        group,
                        known.iter().map(String::as_str),
                    ),
                    known,
                }
            })?;
        terms.push(Term {
            scale: *gain - Vec3A::ONE,
            aov: part.name.clone(),
        });
    }
    Ok(terms)
}

/// Parses `--gain GROUP=GAIN` (one number or `R,G,B`).
pub fn parse_gain(arg: &str) -> Result<(String, Vec3A), PostError> {
    let bad = |expected| PostError::Gain {
        written: arg.to_string(),
        expected,
    };
    let (group, value) = arg.split_once('=').ok_or(bad("GROUP=GAIN"))?;
    let nums: Result<Vec<f32>, _> = value.split(',').map(|v| v.trim().parse::<f32>()).collect();
    let numbers = "a gain of one number or R,G,B after the '='";
    match nums.map_err(|_| bad(numbers))?.as_slice() {
        [g] => Ok((group.trim().to_string(), Vec3A::splat(*g))),
        [r, g, b] => Ok((group.trim().to_string(), Vec3A::new(*r, *g, *b))),
        _ => Err(bad(numbers)),
    }
}

/// One `lightpath comp` run: an expression and/or light-group gains on an EXR.
#[derive(Clone, Debug)]
pub struct CompJob {
    pub exr: PathBuf,
    pub expression: Option<String>,
    /// `GROUP=GAIN` arguments, as given.
    pub gains: Vec<String>,
    /// The split AOV the gains rebalance.
    pub base: String,
    pub output: PathBuf,
    pub exposure: f32,
}

/// What to tell the user about a comp before running it: gains given with an expression
/// add `(gain − 1) · <base>_<group>` terms to it, which the expression may already hold.
pub fn warnings(job: &CompJob) -> Vec<String> {
    match (&job.expression, job.gains.is_empty()) {
        (Some(e), false) => vec![format!(
            "--gain with an expression: the gains add (gain - 1) x {base}_<group> terms to \
             \"{e}\" (they assume the expression holds {base} once; write the terms yourself \
             to be explicit)",
            base = job.base
        )],
        _ => Vec::new(),
    }
}

/// Why relighting a file with gains differs from re-rendering it with the lights changed,
/// read from the settings its header records (nothing for files without them): a clamp
/// cuts a bright contribution to the same value whatever its light's strength, and light
/// selection other than uniform picks each light by every light's power (and several
/// light candidates resample by every light's contribution), so the noise of one light's
/// part depends on the others (README.md, "Relighting equals re-rendering").
pub fn relight_caveat(attributes: &[(String, String)]) -> Option<String> {
    let setting = |key: &str| {
        let name = naming::setting_attribute(key);
        attributes
            .iter()
            .find(|(k, _)| *k == name)
            .map(|(_, v)| v.as_str())
    };
    let mut causes = Vec::new();
    for key in ["clamp_direct", "clamp_indirect"] {
        if let Some(v) = setting(key).filter(|v| v.parse::<f32>().is_ok_and(|c| c > 0.0)) {
            causes.push(format!("{key} = {v}"));
        }
    }
    let clamped = !causes.is_empty();
    let selection = setting("light_selection").filter(|s| *s != "uniform");
    if let Some(s) = selection {
        causes.push(format!("light_selection = {s}"));
    }
    // Resampled candidates are weighed by every light's strength (light_choice.rs).
    let candidates = setting("light_candidates").filter(|m| m.parse::<u32>().is_ok_and(|m| m > 1));
    if let Some(m) = candidates {
        causes.push(format!("light_candidates = {m}"));
    }
    if causes.is_empty() {
        return None;
    }
    let mut effects = Vec::new();
    if clamped {
        effects.push("they differ where contributions were clamped");
    }
    if selection.is_some() || candidates.is_some() {
        effects.push("each light's part carries the noise of the others' choice");
    }
    Some(format!(
        "rendered with {}: relit images equal a re-render with the lights changed only \
         with --light-selection uniform, one light candidate and no clamps; here {}",
        causes.join(", "),
        effects.join(", and ")
    ))
}

/// Runs a comp: writes the output EXR (R, G, B and the input's A) and a PNG beside it,
/// whose path it returns.
pub fn run(job: &CompJob) -> Result<PathBuf, PostError> {
    let png = crate::output::naming::preview_path(&job.output);
    crate::output::target::check_exr_name(&job.output, Some(&png))?;
    for out in [&job.output, &png] {
        crate::output::target::check(out, &[&job.exr])?;
    }
    let exr = read_exr(&job.exr)?;
    let mut terms = match &job.expression {
        Some(e) => parse(e)?,
        None => vec![],
    };
    let gains: Vec<(String, Vec3A)> = job
        .gains
        .iter()
        .map(|g| parse_gain(g))
        .collect::<Result<_, _>>()?;
    if terms.is_empty() {
        terms = gain_terms(&exr, &job.base, &gains)?;
    } else if !gains.is_empty() {
        terms.extend(gain_terms(&exr, &job.base, &gains)?.into_iter().skip(1));
    }
    let rgb = evaluate(&exr, &terms)?;
    let mut channels: Vec<(String, Vec<f32>)> = channel_names(naming::BEAUTY)
        .into_iter()
        .zip(rgb.iter().cloned())
        .collect();
    if let Some(a) = exr.channel(naming::ALPHA) {
        channels.push((naming::ALPHA.into(), a.to_vec()));
    }
    let description = job.expression.clone().unwrap_or_default()
        + &job
            .gains
            .iter()
            .map(|g| format!(" --gain {g}"))
            .collect::<String>();
    let attributes = vec![(
        naming::aov_attribute(naming::BEAUTY),
        format!("comp of {}: {}", job.exr.display(), description.trim()),
    )];
    // A comp of a tile stays that tile of its frame, seen by the same camera.
    let header = exr.derived_header(attributes);
    write_image(
        &job.output,
        exr.width,
        exr.height,
        channels,
        &header,
        Default::default(),
    )?;
    write_png_rgb(
        &png,
        exr.width as u32,
        exr.height as u32,
        &rgb,
        job.exposure,
    )?;
    Ok(png)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::ExrHeader;

    #[test]
    fn the_relighting_caveat_names_what_breaks_relighting() {
        let header = |pairs: &[(&str, &str)]| -> Vec<(String, String)> {
            pairs
                .iter()
                .map(|(k, v)| (naming::setting_attribute(k), v.to_string()))
                .collect()
        };
        let exact = header(&[
            ("clamp_direct", "0"),
            ("clamp_indirect", "0"),
            ("light_selection", "uniform"),
        ]);
        assert_eq!(relight_caveat(&exact), None);
        assert_eq!(
            relight_caveat(&[]),
            None,
            "files without settings: nothing to say"
        );
        let cornell = header(&[
            ("clamp_direct", "0"),
            ("clamp_indirect", "10"),
            ("light_selection", "tree"),
        ]);
        let note = relight_caveat(&cornell).unwrap();
        assert!(note.contains("clamp_indirect = 10"), "{note}");
        assert!(note.contains("light_selection = tree"), "{note}");
        assert!(!note.contains("clamp_direct"), "{note}");
        let clamped = header(&[("clamp_direct", "4"), ("light_selection", "uniform")]);
        let note = relight_caveat(&clamped).unwrap();
        assert!(
            note.contains("clamped") && !note.contains("light_selection"),
            "{note}"
        );
        let resampled = header(&[("light_selection", "uniform"), ("light_candidates", "4")]);
        let note = relight_caveat(&resampled).unwrap();
        assert!(note.contains("light_candidates = 4"), "{note}");
        let one = header(&[("light_selection", "uniform"), ("light_candidates", "1")]);
        assert_eq!(relight_caveat(&one), None);
    }

    #[test]
    fn parses_the_guides_compositing_expressions() {
        let t = parse("beauty - caustics + (1,0.4,0.4)*caustics").unwrap();
        assert_eq!(t.len(), 3);
        assert_eq!(t[1].scale, Vec3A::splat(-1.0));
        assert_eq!(t[2].scale, Vec3A::new(1.0, 0.4, 0.4));
        let t = parse("-0.5*beauty_key + key*2e0").unwrap();
        assert_eq!(t[0].scale, Vec3A::splat(-0.5));
        assert_eq!(t[1].scale, Vec3A::splat(2.0));
        assert!(parse("beauty +").is_err());
        match parse("beauty ^ 2").unwrap_err() {
            PostError::Expression { at, expected, .. } => {
                assert_eq!((at, expected), (7, "'+', '-' or the end"))
            }
            other => panic!("{other}"),
        }
    }

    #[test]
    fn a_comp_of_a_tile_keeps_its_place_in_the_frame() {
        let dir = std::env::temp_dir().join(format!("lightpath-comp-crop-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (input, output) = (dir.join("tile.exr"), dir.join("relit.exr"));
        let (w, h) = (3usize, 2usize);
        let mut channels = Vec::new();
        for aov in ["beauty", "key"] {
            for (c, name) in channel_names(aov).into_iter().enumerate() {
                channels.push((name, vec![0.25 * (c + 1) as f32; w * h]));
            }
        }
        let header = ExrHeader {
            frame: Some([16, 8]),
            origin: [5, 4],
            text: vec![(naming::aov_attribute("key"), "C<L.'key'>".into())],
            ..ExrHeader::default()
        };
        write_image(&input, w, h, channels, &header, Default::default()).unwrap();
        let job = CompJob {
            exr: input,
            expression: Some("beauty + key".into()),
            gains: Vec::new(),
            base: naming::BEAUTY.into(),
            output: output.clone(),
            exposure: 0.0,
        };
        run(&job).unwrap();
        let back = read_exr(&output).unwrap();
        assert_eq!((back.frame, back.origin), ([16, 8], [5, 4]));
        assert_eq!((back.width, back.height), (w, h));
        assert_eq!(back.channel("R").unwrap()[0], 0.5);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
