//! Which AOVs a render produces: the one owner of that decision. The request is plain
//! data (what the command line and the scene file asked for), so the plan depends on
//! neither clap nor the scene description's types.

use super::{assemble, bounces, standard, AovSpec};
use crate::aov::naming::BEAUTY;
use std::fmt;

/// Above this many AOVs a render warns: each AOV costs film memory and EXR size.
pub const MANY_AOVS: usize = 64;

/// The largest `--bounces`: `bounce<K>plus` is `C[DSV]{K,}[<L.>O]`, and quantifier bounds
/// stop at 64.
pub const MAX_BOUNCES: u32 = 63;

/// What was asked for.
#[derive(Clone, Debug, Default)]
pub struct PlanRequest {
    /// The standard set of docs/lpe.md#standard-aovs.
    pub standard: bool,
    /// The scene's `[aovs]`, in order: name and definition.
    pub scene_aovs: Vec<(String, String)>,
    /// The command line's `--aov`s (after the scene's, so they replace its names).
    pub extra: Vec<AovSpec>,
    /// `--bounces K`.
    pub bounces: Option<u32>,
    /// AOVs to split per light group (command line first, then the scene's).
    pub split: Vec<String>,
    pub scene_split: Vec<String>,
    /// Split beauty per light group (command line or scene).
    pub light_groups: bool,
    /// Every light's groups, as the scene lists them (duplicates allowed).
    pub scene_light_groups: Vec<String>,
}

/// The plan: the AOVs in order, and warnings to show.
#[derive(Clone, Debug)]
pub struct AovPlan {
    pub specs: Vec<AovSpec>,
    pub warnings: Vec<String>,
}

/// A request that cannot be planned.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum PlanError {
    /// An `--aov` argument that is neither `NAME=DEF` nor a standard name.
    BadAov { arg: String, message: String },
    /// A light-group split names an AOV the render does not have.
    UnknownSplit(String),
    /// `--bounces K` outside 1 ..= 63 (a quantifier bound of docs/lpe.md#quantifiers is at most 64).
    Bounces(u32),
    /// Two `--aov`s of one name: which one was meant cannot be guessed.
    DuplicateAov(String),
}

impl fmt::Display for PlanError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PlanError::BadAov { arg, message } => write!(f, "--aov {arg}: {message}"),
            PlanError::UnknownSplit(name) => write!(
                f,
                "--light-group-aovs names '{name}', which is not an AOV of this render"
            ),
            PlanError::DuplicateAov(name) => write!(
                f,
                "--aov {name} is given twice: name each AOV once (an --aov replaces an AOV \
                 of the scene or the standard set of that name)"
            ),
            PlanError::Bounces(k) => write!(
                f,
                "--bounces {k}: expected 1 to {MAX_BOUNCES} (bounce0 … bounce<K-1> and bounce<K>plus)"
            ),
        }
    }
}

impl std::error::Error for PlanError {}

/// Parses `--aov` arguments.
pub fn parse_aov_args(args: &[String]) -> Result<Vec<AovSpec>, PlanError> {
    args.iter()
        .map(|a| {
            AovSpec::parse(a).map_err(|e| PlanError::BadAov {
                arg: a.clone(),
                message: e.0,
            })
        })
        .collect()
}

impl AovPlan {
    /// Beauty, the standard set, the scene's, the command line's, the bounces; then the
    /// light-group splits marked on the AOVs they split.
    pub fn build(req: &PlanRequest) -> Result<AovPlan, PlanError> {
        let mut specs = Vec::new();
        if req.standard {
            specs.extend(standard());
        }
        specs.extend(
            req.scene_aovs
                .iter()
                .map(|(n, d)| AovSpec::new(n.clone(), d.clone())),
        );
        for (i, a) in req.extra.iter().enumerate() {
            if req.extra[..i].iter().any(|b| b.name == a.name) {
                return Err(PlanError::DuplicateAov(a.name.clone()));
            }
        }
        specs.extend(req.extra.iter().cloned());
        if let Some(k) = req.bounces {
            if !(1..=MAX_BOUNCES).contains(&k) {
                return Err(PlanError::Bounces(k));
            }
            specs.extend(bounces(k));
        }
        let mut specs = assemble(specs);
        let mut split: Vec<String> = req.split.clone();
        split.extend(
            req.scene_split
                .iter()
                .filter(|n| !req.split.contains(n))
                .cloned(),
        );
        if req.light_groups {
            split.push(BEAUTY.into());
        }
        split.sort();
        split.dedup();
        for name in &split {
            match specs.iter_mut().find(|s| &s.name == name) {
                Some(s) => s.split_light_groups = true,
                None => return Err(PlanError::UnknownSplit(name.clone())),
            }
        }
        let mut warnings = Vec::new();
        if !split.is_empty() {
            let mut groups: Vec<&String> = req.scene_light_groups.iter().collect();
            groups.sort();
            groups.dedup();
            let total = specs.len() + split.len() * (groups.len() + 1);
            if total > MANY_AOVS {
                warnings.push(format!("the light-group split makes {total} AOVs"));
            }
        }
        Ok(AovPlan { specs, warnings })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plan_orders_and_splits() {
        let req = PlanRequest {
            scene_aovs: vec![("key".into(), "C<.>*<L.'key'>".into())],
            extra: vec![AovSpec::new("key", "CO")],
            bounces: Some(2),
            light_groups: true,
            ..Default::default()
        };
        let plan = AovPlan::build(&req).unwrap();
        let names: Vec<&str> = plan.specs.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(
            names,
            ["beauty", "key", "bounce0", "bounce1", "bounce2plus"]
        );
        assert_eq!(plan.specs[1].definition, "CO");
        assert!(plan.specs[0].split_light_groups);
        assert!(plan.warnings.is_empty());
    }

    #[test]
    fn two_aovs_of_one_name_are_refused() {
        let req = PlanRequest {
            extra: vec![AovSpec::new("key", "C<RD>L"), AovSpec::new("key", "C<RS>L")],
            ..Default::default()
        };
        assert_eq!(
            AovPlan::build(&req).unwrap_err(),
            PlanError::DuplicateAov("key".into())
        );
        // One --aov replacing a standard AOV is the user's definition, not a duplicate.
        let req = PlanRequest {
            standard: true,
            extra: vec![AovSpec::new("directDiffuse", "C<RD>L")],
            ..Default::default()
        };
        let plan = AovPlan::build(&req).unwrap();
        let dd: Vec<_> = plan
            .specs
            .iter()
            .filter(|s| s.name == "directDiffuse")
            .collect();
        assert_eq!(dd.len(), 1);
        assert_eq!(dd[0].definition, "C<RD>L");
    }

    #[test]
    fn unknown_split_and_many_aovs() {
        let req = PlanRequest {
            split: vec!["x".into()],
            ..Default::default()
        };
        assert_eq!(
            AovPlan::build(&req).unwrap_err().to_string(),
            "--light-group-aovs names 'x', which is not an AOV of this render"
        );
        let req = PlanRequest {
            standard: true,
            light_groups: true,
            scene_light_groups: (0..70).map(|i| format!("g{i}")).collect(),
            ..Default::default()
        };
        assert_eq!(AovPlan::build(&req).unwrap().warnings.len(), 1);
        assert!(parse_aov_args(&["C<RD>L".into()]).is_err());
    }
}
