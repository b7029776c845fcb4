//! Subset construction over event classes, then Hopcroft minimisation.

use crate::nfa::{Nfa, NfaState, NfaStateId};
use std::collections::HashMap;

/// A dense DFA: `next[state * classes + class]`. State 0 is dead (no rule can match any
/// continuation), `start` is where every path begins.
#[derive(Clone, Debug)]
pub struct Dfa {
    pub classes: usize,
    pub next: Vec<u32>,
    /// Rules accepted in each state, sorted.
    pub accept: Vec<Vec<u32>>,
    pub start: u32,
}

impl Dfa {
    pub fn len(&self) -> usize {
        self.accept.len()
    }
    pub fn is_empty(&self) -> bool {
        self.accept.is_empty()
    }
}

/// The DFA would exceed the state limit; the count reached is given.
#[derive(Debug)]
pub struct StateLimit(pub usize);

/// How subsets of NFA states are stored: bitsets with each state's closure precomputed
/// (fast, for NFAs up to `DENSE_LIMIT` states), or sorted id lists for larger ones.
enum Subsets {
    Dense {
        words: usize,
        closures: Vec<Vec<u64>>,
    },
    Sparse,
}

const DENSE_LIMIT: usize = 8192;

impl Subsets {
    fn new(nfa: &Nfa) -> Subsets {
        let n = nfa.states.len();
        if n > DENSE_LIMIT {
            return Subsets::Sparse;
        }
        let words = n.div_ceil(64).max(1);
        let mut mark = Vec::new();
        let closures = (0..n as NfaStateId)
            .map(|s| {
                let mut bits = vec![0u64; words];
                for t in nfa.closure([s], &mut mark) {
                    bits[t as usize / 64] |= 1 << (t % 64);
                }
                bits
            })
            .collect();
        Subsets::Dense { words, closures }
    }

    /// The epsilon closure of `targets`, as a hashable key.
    fn closure(
        &self,
        nfa: &Nfa,
        targets: impl Iterator<Item = NfaStateId>,
        mark: &mut Vec<bool>,
    ) -> Vec<u64> {
        match self {
            Subsets::Dense { words, closures } => {
                let mut bits = vec![0u64; *words];
                for t in targets {
                    for (b, c) in bits.iter_mut().zip(&closures[t as usize]) {
                        *b |= c;
                    }
                }
                bits
            }
            Subsets::Sparse => nfa
                .closure(targets, mark)
                .into_iter()
                .map(u64::from)
                .collect(),
        }
    }

    fn members(&self, set: &[u64]) -> Vec<NfaStateId> {
        match self {
            Subsets::Dense { .. } => set
                .iter()
                .enumerate()
                .flat_map(|(w, &bits)| {
                    (0..64)
                        .filter(move |b| bits & (1 << b) != 0)
                        .map(move |b| (w * 64 + b) as NfaStateId)
                })
                .collect(),
            Subsets::Sparse => set.iter().map(|&s| s as NfaStateId).collect(),
        }
    }
}

/// Determinises `nfa` over event classes, given as signatures: bit `p` of a class's
/// signature is set when its events satisfy predicate `p`.
pub fn determinize(nfa: &Nfa, class_sigs: &[Vec<u64>], limit: usize) -> Result<Dfa, StateLimit> {
    let classes = class_sigs.len();
    let pred_words = nfa.preds.len().div_ceil(64).max(1);
    let subsets = Subsets::new(nfa);
    let mut mark = Vec::new();
    let mut ids: HashMap<Vec<u64>, u32> = HashMap::new();
    let mut sets: Vec<Vec<u64>> = Vec::new();
    // The dead state first: the empty set.
    let empty = subsets.closure(nfa, std::iter::empty(), &mut mark);
    ids.insert(empty.clone(), 0);
    sets.push(empty);
    let start_set = subsets.closure(nfa, std::iter::once(nfa.start), &mut mark);
    let start = *ids.entry(start_set.clone()).or_insert_with(|| {
        sets.push(start_set);
        (sets.len() - 1) as u32
    });
    let mut next = Vec::new();
    let mut todo = 0usize;
    while todo < sets.len() {
        // Event transitions out of this subset.
        let moves: Vec<(u32, NfaStateId)> = subsets
            .members(&sets[todo])
            .into_iter()
            .filter_map(|s| match &nfa.states[s as usize] {
                NfaState::Event { pred, next } => Some((*pred, *next)),
                _ => None,
            })
            .collect();
        // A class's successor depends only on which of this subset's predicates hold for
        // it: compute each distinct successor once.
        let mut mask = vec![0u64; pred_words];
        for (p, _) in &moves {
            mask[*p as usize / 64] |= 1 << (p % 64);
        }
        let mut by_key: HashMap<Vec<u64>, u32> = HashMap::new();
        for sig in class_sigs {
            let key: Vec<u64> = sig.iter().zip(&mask).map(|(s, m)| s & m).collect();
            if let Some(&id) = by_key.get(&key) {
                next.push(id);
                continue;
            }
            let targets = moves
                .iter()
                .filter(|(p, _)| key[*p as usize / 64] & (1 << (p % 64)) != 0)
                .map(|(_, n)| *n);
            let set = subsets.closure(nfa, targets, &mut mark);
            let id = match ids.get(&set) {
                Some(&id) => id,
                None => {
                    if sets.len() >= limit {
                        return Err(StateLimit(sets.len() + 1));
                    }
                    let id = sets.len() as u32;
                    ids.insert(set.clone(), id);
                    sets.push(set);
                    id
                }
            };
            by_key.insert(key, id);
            next.push(id);
        }
        todo += 1;
    }
    let accept = sets
        .iter()
        .map(|set| {
            let mut rules: Vec<u32> = subsets
                .members(set)
                .into_iter()
                .filter_map(|s| match nfa.states[s as usize] {
                    NfaState::Match(r) => Some(r),
                    _ => None,
                })
                .collect();
            rules.sort_unstable();
            rules
        })
        .collect();
    Ok(Dfa {
        classes,
        next,
        accept,
        start,
    })
}

/// Hopcroft's partition refinement: merges states with the same future (same accepted
/// rule sets after every continuation). The dead state stays state 0.
pub fn minimize(dfa: &Dfa) -> Dfa {
    let n = dfa.len();
    let k = dfa.classes;
    if n == 0 {
        return dfa.clone();
    }
    let (mut block_of, mut blocks) = initial_partition(dfa);
    let (inv_start, inv) = inverse_transitions(dfa);
    let mut in_work = vec![true; blocks.len()];
    let mut work: Vec<u32> = (0..blocks.len() as u32).collect();
    let mut marked = vec![false; n];
    let mut touched: Vec<u32> = Vec::new();
    let mut marked_count: Vec<u32> = vec![0; blocks.len()];
    while let Some(a) = work.pop() {
        in_work[a as usize] = false;
        let splitter = blocks[a as usize].clone();
        for c in 0..k {
            // X = states that go into the splitter on class c.
            for &t in &splitter {
                let i = t as usize * k + c;
                for &s in &inv[inv_start[i] as usize..inv_start[i + 1] as usize] {
                    if !marked[s as usize] {
                        marked[s as usize] = true;
                        let b = block_of[s as usize];
                        if marked_count[b as usize] == 0 {
                            touched.push(b);
                        }
                        marked_count[b as usize] += 1;
                    }
                }
            }
            for &b in &touched {
                let count = marked_count[b as usize] as usize;
                marked_count[b as usize] = 0;
                if count == blocks[b as usize].len() {
                    continue;
                }
                let (inside, outside): (Vec<u32>, Vec<u32>) = blocks[b as usize]
                    .iter()
                    .partition(|&&s| marked[s as usize]);
                let new_id = blocks.len() as u32;
                for &s in &inside {
                    block_of[s as usize] = new_id;
                }
                blocks[b as usize] = outside;
                blocks.push(inside);
                marked_count.push(0);
                if in_work[b as usize] {
                    in_work.push(true);
                    work.push(new_id);
                } else {
                    // Only the smaller half needs to split others further.
                    let smaller = if blocks[new_id as usize].len() <= blocks[b as usize].len() {
                        new_id
                    } else {
                        b
                    };
                    in_work.push(false);
                    in_work[smaller as usize] = true;
                    work.push(smaller);
                }
            }
            for &b in &touched {
                for &s in &blocks[b as usize] {
                    marked[s as usize] = false;
                }
            }
            // The new halves were cleared above only if they kept id b; clear the rest.
            for s in splitter.iter().flat_map(|&t| {
                let base = t as usize * k + c;
                inv[inv_start[base] as usize..inv_start[base + 1] as usize]
                    .iter()
                    .copied()
            }) {
                marked[s as usize] = false;
            }
            touched.clear();
        }
    }
    quotient(dfa, &blocks, &block_of)
}

/// Hopcroft's initial partition: states grouped by accepted rule set. Returns each
/// state's block and each block's states.
fn initial_partition(dfa: &Dfa) -> (Vec<u32>, Vec<Vec<u32>>) {
    let n = dfa.len();
    let mut block_of = vec![0u32; n];
    let mut blocks: Vec<Vec<u32>> = Vec::new();
    {
        let mut by_accept: HashMap<&[u32], u32> = HashMap::new();
        for (s, accept) in dfa.accept.iter().enumerate() {
            let b = *by_accept.entry(accept).or_insert_with(|| {
                blocks.push(Vec::new());
                (blocks.len() - 1) as u32
            });
            block_of[s] = b;
            blocks[b as usize].push(s as u32);
        }
    }
    (block_of, blocks)
}

/// Inverse transitions: for class c and target t, the states that go to t on c are
/// `inv[inv_start[t * k + c]..inv_start[t * k + c + 1]]`.
fn inverse_transitions(dfa: &Dfa) -> (Vec<u32>, Vec<u32>) {
    let (n, k) = (dfa.len(), dfa.classes);
    let mut inv_start = vec![0u32; n * k + 1];
    for s in 0..n {
        for c in 0..k {
            let t = dfa.next[s * k + c] as usize;
            inv_start[t * k + c + 1] += 1;
        }
    }
    for i in 1..inv_start.len() {
        inv_start[i] += inv_start[i - 1];
    }
    let mut fill = inv_start.clone();
    let mut inv = vec![0u32; n * k];
    for s in 0..n {
        for c in 0..k {
            let t = dfa.next[s * k + c] as usize;
            inv[fill[t * k + c] as usize] = s as u32;
            fill[t * k + c] += 1;
        }
    }
    (inv_start, inv)
}

/// The automaton whose states are the final partition's blocks: the dead state's block
/// first (state 0), then in order of first appearance.
fn quotient(dfa: &Dfa, blocks: &[Vec<u32>], block_of: &[u32]) -> Dfa {
    let k = dfa.classes;
    let mut new_id = vec![u32::MAX; blocks.len()];
    let mut order = Vec::with_capacity(blocks.len());
    let mut assign = |b: u32, order: &mut Vec<u32>| {
        if new_id[b as usize] == u32::MAX {
            new_id[b as usize] = order.len() as u32;
            order.push(b);
        }
    };
    assign(block_of[0], &mut order);
    assign(block_of[dfa.start as usize], &mut order);
    for &b in block_of {
        assign(b, &mut order);
    }
    let mut next = Vec::with_capacity(order.len() * k);
    let mut accept = Vec::with_capacity(order.len());
    for &b in &order {
        let rep = blocks[b as usize][0] as usize;
        for c in 0..k {
            next.push(new_id[block_of[dfa.next[rep * k + c] as usize] as usize]);
        }
        accept.push(dfa.accept[rep].clone());
    }
    Dfa {
        classes: k,
        next,
        accept,
        start: new_id[block_of[dfa.start as usize] as usize],
    }
}
