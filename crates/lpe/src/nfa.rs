//! Thompson construction: one NFA for all rules, one match state per rule. The reference
//! simulator here is what the DFA is tested against.

use crate::event::Event;
use crate::hir::{Hir, Pred};
use std::collections::HashMap;

pub type NfaStateId = u32;

#[derive(Clone, Debug)]
pub enum NfaState {
    /// Epsilon transitions.
    Split(Vec<NfaStateId>),
    /// Consume one event satisfying predicate `pred`.
    Event { pred: u32, next: NfaStateId },
    /// Rule `rule` matches when the path ends here.
    Match(u32),
}

#[derive(Clone, Debug)]
pub struct Nfa {
    pub states: Vec<NfaState>,
    pub start: NfaStateId,
    /// Distinct predicates, indexed by `NfaState::Event::pred`.
    pub preds: Vec<Pred>,
    pub rule_count: usize,
}

/// The NFA would exceed its size limit.
#[derive(Debug)]
pub struct TooLarge;

pub struct NfaBuilder {
    states: Vec<NfaState>,
    preds: Vec<Pred>,
    pred_ids: HashMap<Pred, u32>,
    starts: Vec<NfaStateId>,
    limit: usize,
}

impl NfaBuilder {
    pub fn new(limit: usize) -> NfaBuilder {
        NfaBuilder {
            states: Vec::new(),
            preds: Vec::new(),
            pred_ids: HashMap::new(),
            starts: Vec::new(),
            limit,
        }
    }

    /// Adds one rule; its id is the order of addition.
    pub fn add_rule(&mut self, hir: &Hir) -> Result<(), TooLarge> {
        let rule = self.starts.len() as u32;
        let accept = self.push(NfaState::Match(rule))?;
        let start = self.compile(hir, accept)?;
        self.starts.push(start);
        Ok(())
    }

    pub fn build(mut self) -> Result<Nfa, TooLarge> {
        let rule_count = self.starts.len();
        let starts = std::mem::take(&mut self.starts);
        let start = self.push(NfaState::Split(starts))?;
        Ok(Nfa {
            states: self.states,
            start,
            preds: self.preds,
            rule_count,
        })
    }

    fn push(&mut self, s: NfaState) -> Result<NfaStateId, TooLarge> {
        if self.states.len() >= self.limit {
            return Err(TooLarge);
        }
        self.states.push(s);
        Ok((self.states.len() - 1) as NfaStateId)
    }

    /// Compiles `hir` so that it continues to `next`; returns its entry state.
    fn compile(&mut self, hir: &Hir, next: NfaStateId) -> Result<NfaStateId, TooLarge> {
        match hir {
            Hir::Event(pred) => {
                let id = match self.pred_ids.get(pred) {
                    Some(&id) => id,
                    None => {
                        let id = self.preds.len() as u32;
                        self.preds.push(pred.clone());
                        self.pred_ids.insert(pred.clone(), id);
                        id
                    }
                };
                self.push(NfaState::Event { pred: id, next })
            }
            Hir::Concat(parts) => {
                let mut next = next;
                for part in parts.iter().rev() {
                    next = self.compile(part, next)?;
                }
                Ok(next)
            }
            Hir::Alt(options) => {
                let entries = options
                    .iter()
                    .map(|o| self.compile(o, next))
                    .collect::<Result<_, _>>()?;
                self.push(NfaState::Split(entries))
            }
            Hir::Repeat { hir, min, max } => {
                let mut tail = match max {
                    None => {
                        let lp = self.push(NfaState::Split(Vec::new()))?;
                        let body = self.compile(hir, lp)?;
                        self.states[lp as usize] = NfaState::Split(vec![body, next]);
                        lp
                    }
                    // Nested optionals, (x(x)?)?, so that {0,m} means exactly 0 to m copies.
                    Some(m) => {
                        let mut t = next;
                        for _ in 0..m.saturating_sub(*min) {
                            let body = self.compile(hir, t)?;
                            t = self.push(NfaState::Split(vec![body, next]))?;
                        }
                        t
                    }
                };
                for _ in 0..*min {
                    tail = self.compile(hir, tail)?;
                }
                Ok(tail)
            }
        }
    }
}

impl Nfa {
    /// The epsilon closure of `seeds`, sorted and unique.
    pub fn closure(
        &self,
        seeds: impl IntoIterator<Item = NfaStateId>,
        mark: &mut Vec<bool>,
    ) -> Vec<NfaStateId> {
        // `mark` is all false between calls: only the visited entries are reset below.
        mark.resize(self.states.len(), false);
        let mut stack: Vec<NfaStateId> = seeds.into_iter().collect();
        let mut out = Vec::new();
        while let Some(s) = stack.pop() {
            if std::mem::replace(&mut mark[s as usize], true) {
                continue;
            }
            out.push(s);
            if let NfaState::Split(next) = &self.states[s as usize] {
                stack.extend(next.iter().copied());
            }
        }
        for &s in &out {
            mark[s as usize] = false;
        }
        out.sort_unstable();
        out
    }

    /// The rules matching the whole path, by direct NFA simulation (the reference).
    pub fn simulate(&self, path: &[Event]) -> Vec<u32> {
        let mut mark = Vec::new();
        let mut set = self.closure([self.start], &mut mark);
        for e in path {
            let holds: Vec<bool> = self.preds.iter().map(|p| p.matches(e)).collect();
            let next: Vec<NfaStateId> = set
                .iter()
                .filter_map(|&s| match &self.states[s as usize] {
                    NfaState::Event { pred, next } if holds[*pred as usize] => Some(*next),
                    _ => None,
                })
                .collect();
            set = self.closure(next, &mut mark);
            if set.is_empty() {
                break;
            }
        }
        let mut rules: Vec<u32> = set
            .iter()
            .filter_map(|&s| match self.states[s as usize] {
                NfaState::Match(r) => Some(r),
                _ => None,
            })
            .collect();
        rules.sort_unstable();
        rules
    }

    /// True if rule `rule` accepts at least one path (its match state is reachable
    /// through events whose predicates can hold).
    pub fn rule_can_match(&self, rule: u32) -> bool {
        let mut seen = vec![false; self.states.len()];
        let mut stack = vec![self.start];
        while let Some(s) = stack.pop() {
            if std::mem::replace(&mut seen[s as usize], true) {
                continue;
            }
            match &self.states[s as usize] {
                NfaState::Split(next) => stack.extend(next.iter().copied()),
                NfaState::Event { pred, next } => {
                    if !self.preds[*pred as usize].is_empty() {
                        stack.push(*next)
                    }
                }
                NfaState::Match(r) if *r == rule => return true,
                NfaState::Match(_) => {}
            }
        }
        false
    }
}
