//! Additive compositing from an EXR's AOVs (`lightpath comp`) and the partition checks
//! of `lightpath aovs`: relighting by addition and subtraction, never a re-render.

use crate::output::{channel_names, ExrContents};
use glam::Vec3A;

/// One term of a compositing expression: `scale * aov`.
#[derive(Clone, Debug, PartialEq)]
pub struct Term {
    pub scale: Vec3A,
    pub aov: String,
}

/// Parses `beauty + 0.5*beauty_key - indirectSpecular + (1,0.4,0.4)*caustics`.
pub fn parse(expr: &str) -> Result<Vec<Term>, String> {
    let mut p = Cursor {
        s: expr.as_bytes(),
        i: 0,
    };
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
    fn error(&self, expected: &str) -> String {
        format!("at {}: expected {expected}", self.i)
    }
    fn number(&mut self) -> Result<f32, String> {
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
    fn factor(&mut self) -> Result<Vec3A, String> {
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
    fn name(&mut self) -> Result<String, String> {
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
pub fn aov_planes<'a>(exr: &'a ExrContents, aov: &str) -> Result<[&'a [f32]; 3], String> {
    let names = channel_names(aov);
    let mut out: [&[f32]; 3] = [&[], &[], &[]];
    for (slot, name) in out.iter_mut().zip(&names) {
        *slot = exr.channel(name).ok_or_else(|| {
            let known: Vec<String> = exr.aovs().into_iter().map(|(n, _)| n).collect();
            format!("the EXR has no AOV '{aov}' (channel {name}); it has {known:?}")
        })?;
    }
    Ok(out)
}

/// Evaluates a sum of scaled AOVs, pixel by pixel.
pub fn evaluate(exr: &ExrContents, terms: &[Term]) -> Result<[Vec<f32>; 3], String> {
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
pub fn gain_terms(base: &str, gains: &[(String, Vec3A)]) -> Vec<Term> {
    let mut terms = vec![Term {
        scale: Vec3A::ONE,
        aov: base.to_string(),
    }];
    for (group, gain) in gains {
        let part = if group == "_default" {
            crate::aov::split_name(base, None)
        } else {
            crate::aov::split_name(base, Some(group))
        };
        terms.push(Term {
            scale: *gain - Vec3A::ONE,
            aov: part,
        });
    }
    terms
}

/// A partition of an AOV that the EXR holds, and how far its parts are from summing to it.
#[derive(Clone, Debug)]
pub struct PartitionCheck {
    pub whole: String,
    pub parts: Vec<String>,
    /// max over pixels and channels of |Σ parts − whole| / max(|whole|, 1e-3).
    pub max_relative_error: f32,
}

/// Finds the known partitions in an EXR (the standard set, light-group splits, bounce
/// AOVs) and measures each.
pub fn check_partitions(exr: &ExrContents) -> Vec<PartitionCheck> {
    let aovs = exr.aovs();
    let has = |n: &str| aovs.iter().any(|(a, _)| a == n);
    let mut candidates: Vec<(String, Vec<String>)> = Vec::new();
    if has("beauty") && lpe::BEAUTY_PARTITION.iter().all(|n| has(n)) {
        candidates.push((
            "beauty".into(),
            lpe::BEAUTY_PARTITION
                .iter()
                .map(|s| s.to_string())
                .collect(),
        ));
    }
    for (name, _) in &aovs {
        if let Some(whole) = name.strip_suffix("__default") {
            if !has(whole) {
                continue;
            }
            let prefix = format!("{whole}_");
            let parts: Vec<String> = aovs
                .iter()
                .filter(|(n, d)| {
                    n.starts_with(&prefix)
                        && (d.contains("(light group '") || d.contains("(lights without a group)"))
                })
                .map(|(n, _)| n.clone())
                .collect();
            candidates.push((whole.to_string(), parts));
        }
    }
    if let Some((plus, _)) = aovs
        .iter()
        .find(|(n, _)| n.starts_with("bounce") && n.ends_with("plus"))
    {
        if let Ok(k) = plus["bounce".len()..plus.len() - "plus".len()].parse::<u32>() {
            let mut parts: Vec<String> = (0..k).map(|i| format!("bounce{i}")).collect();
            parts.push(plus.clone());
            if has("beauty") && parts.iter().all(|p| has(p)) {
                candidates.push(("beauty".into(), parts));
            }
        }
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
                    worst = worst.max((s - v).abs() / v.abs().max(1e-3));
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

/// Merges EXRs of one frame rendered as different sample ranges: each channel is the
/// average of the inputs weighted by their sample counts (header `lightpath/spp`).
/// Returns the merged sample count.
pub fn merge(inputs: &[std::path::PathBuf], output: &std::path::Path) -> Result<u64, String> {
    use crate::output::{read_exr, write_channels, ExrOptions};
    if inputs.is_empty() {
        return Err("give the EXRs to merge".into());
    }
    let spp_of = |exr: &ExrContents, path: &std::path::Path| -> Result<u64, String> {
        exr.attributes
            .iter()
            .find(|(k, _)| k == "lightpath/spp")
            .and_then(|(_, v)| v.parse().ok())
            .ok_or_else(|| {
                format!(
                    "{} has no lightpath/spp header: not a Lightpath render",
                    path.display()
                )
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
        .find(|(k, _)| k == "lightpath/first_sample")
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
            .find(|(k, _)| k == "lightpath/first_sample")
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
        .filter(|(k, _)| k != "lightpath/spp" && k != "lightpath/first_sample")
        .cloned()
        .collect();
    attributes.push(("lightpath/spp".into(), total.to_string()));
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

#[cfg(test)]
mod tests {
    use super::*;

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
        assert!(parse("beauty ^ 2").is_err());
    }
}
