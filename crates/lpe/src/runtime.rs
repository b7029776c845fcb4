//! The compiled, immutable automaton a renderer steps at every path vertex, and the
//! compiler that builds it from AOV definitions.

use crate::dfa::{determinize, minimize};
use crate::error::{Error, ErrorKind, Span};
use crate::event::{all_scatters, Event, EventType};
use crate::hir::{lower, Hir, Pred, RESERVED_TYPES};
use crate::nfa::{Nfa, NfaBuilder, NfaState};
use crate::prefix::{standard_name, Flags};
use crate::syntax::ast::{Body, Definition};
use crate::syntax::{parse_definition, print_definition};
use std::collections::HashMap;

/// The index of a rule (an AOV definition) in the order it was added.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct RuleId(pub u32);

/// An event class: all events that every rule treats alike. Obtained from
/// [`Automaton::classify`], once per distinct event (at scene build, not per vertex).
/// The default is class 0, a placeholder for what a renderer classifies later.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct ClassId(u32);

impl ClassId {
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// The automaton state of a path prefix: one `u32`, pre-multiplied by the class count so
/// that a step is one table load.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct StateId(u32);

/// One parsed and lowered AOV definition.
#[derive(Clone, Debug)]
pub struct Rule {
    /// `NAME` of `NAME=…`, if given.
    pub name: Option<String>,
    /// The definition as written.
    pub source: String,
    /// The expression after expanding standard names, without prefixes.
    pub expression: String,
    /// Prefixes, the written ones merged with a standard name's.
    pub flags: Flags,
    pub(crate) definition: Definition,
    pub(crate) hir: Hir,
}

impl Rule {
    /// Parses and lowers one definition.
    pub fn parse(source: &str) -> Result<Rule, Error> {
        let definition = parse_definition(source)?;
        let mut flags: Flags = definition.prefixes.iter().copied().collect();
        let (expr_def, expression) = match &definition.body {
            Body::Expr(_) => {
                let bare = Definition {
                    name: None,
                    lpe_marker: false,
                    prefixes: vec![],
                    body: definition.body.clone(),
                };
                (definition.clone(), print_definition(&bare))
            }
            Body::Standard(name) => {
                let (_, text) = standard_name(name).expect("the parser only accepts known names");
                let std_def = parse_definition(text).expect("standard definitions are valid");
                for p in &std_def.prefixes {
                    flags.insert(*p);
                }
                let bare = Definition {
                    name: None,
                    lpe_marker: false,
                    prefixes: vec![],
                    body: std_def.body.clone(),
                };
                (std_def, print_definition(&bare))
            }
        };
        let Body::Expr(expr) = &expr_def.body else {
            unreachable!("standard names expand to expressions")
        };
        let hir = lower(expr);
        Ok(Rule {
            name: definition.name.clone(),
            source: source.to_string(),
            expression,
            flags,
            definition,
            hir,
        })
    }

    /// The syntax tree as written.
    pub fn definition(&self) -> &Definition {
        &self.definition
    }

    /// The lowered expression.
    pub fn hir(&self) -> &Hir {
        &self.hir
    }
}

/// A note about a valid rule that will probably not do what was meant.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Warning {
    pub rule: RuleId,
    pub message: String,
}

/// Sizes of the compilation stages, for `lpe explain` and benchmarks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stats {
    pub nfa_states: usize,
    pub predicates: usize,
    pub classes: usize,
    pub dfa_states: usize,
    pub min_dfa_states: usize,
}

/// What a renderer can emit (docs/lpe.md#paths-and-events): the event types its paths contain. Rules that
/// need other types get a warning: they would stay black.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Profile {
    emits: u8,
}

impl Profile {
    /// Paths of camera, reflection, transmission, light, emission and volume events; no
    /// background (`B`) events.
    pub const GENERIC: Profile = Profile {
        emits: !RESERVED_TYPES,
    };

    /// A renderer that emits exactly these event types.
    pub fn new(emits: &[EventType]) -> Profile {
        Profile {
            emits: emits.iter().fold(0, |bits, t| bits | t.bit()),
        }
    }

    pub fn emits(&self, ty: EventType) -> bool {
        self.emits & ty.bit() != 0
    }
}

impl Default for Profile {
    fn default() -> Self {
        Profile::GENERIC
    }
}

/// Builds an [`Automaton`] from rules and the events it must classify.
#[derive(Clone, Debug)]
pub struct Compiler {
    profile: Profile,
    rules: Vec<Rule>,
    vocabulary: Vec<Event>,
    state_limit: usize,
    nfa_limit: usize,
    minimize: bool,
    default_alphabet: bool,
}

impl Default for Compiler {
    fn default() -> Self {
        Compiler::new()
    }
}

/// Default limit on DFA states built by subset construction (docs/lpe.md#errors).
pub const DEFAULT_STATE_LIMIT: usize = 10_000;

impl Compiler {
    pub fn new() -> Compiler {
        Compiler {
            profile: Profile::GENERIC,
            rules: Vec::new(),
            vocabulary: Vec::new(),
            state_limit: DEFAULT_STATE_LIMIT,
            nfa_limit: 200_000,
            minimize: true,
            default_alphabet: true,
        }
    }

    /// The most DFA states subset construction may build before giving up with an error.
    pub fn state_limit(mut self, limit: usize) -> Compiler {
        self.state_limit = limit.max(2);
        self
    }

    /// Whether the alphabet includes the default events (every event of the shapes the
    /// profile emits, docs/lpe.md#paths-and-events: `C`, `L`, `O` (and `V`, `B` if it emits them) without
    /// scatter, `R`/`T` with any lobe; each with no label or one label the rules name). A renderer that passes
    /// its whole scene as the vocabulary turns this off for the smallest table.
    pub fn default_alphabet(mut self, on: bool) -> Compiler {
        self.default_alphabet = on;
        self
    }

    /// What the renderer can emit, for the warnings (default: [`Profile::GENERIC`]).
    pub fn profile(mut self, profile: Profile) -> Compiler {
        self.profile = profile;
        self
    }

    /// Whether to minimise the DFA (on by default; off only to test minimisation).
    pub fn minimize(mut self, on: bool) -> Compiler {
        self.minimize = on;
        self
    }

    /// Parses a definition and adds it as the next rule.
    pub fn add(&mut self, definition: &str) -> Result<RuleId, Error> {
        let rule = Rule::parse(definition)?;
        Ok(self.add_rule(rule))
    }

    pub fn add_rule(&mut self, rule: Rule) -> RuleId {
        self.rules.push(rule);
        RuleId(self.rules.len() as u32 - 1)
    }

    /// Events the automaton must classify beyond the default alphabet. A renderer passes
    /// every event its scene can emit; events with several labels, or of shapes renderers
    /// do not emit (`<LD>`), need this.
    pub fn vocabulary(&mut self, events: impl IntoIterator<Item = Event>) -> &mut Compiler {
        self.vocabulary.extend(events);
        self
    }

    pub fn rules(&self) -> &[Rule] {
        &self.rules
    }

    pub fn compile(&self) -> Result<Automaton, Error> {
        let whole = |rules: &[Rule]| {
            let len = rules.last().map_or(0, |r| r.source.len());
            Span::new(0, len)
        };
        let too_large = |what: String| Error::new(ErrorKind::StateLimit, whole(&self.rules), what);
        let mut builder = NfaBuilder::new(self.nfa_limit);
        for rule in &self.rules {
            builder.add_rule(&rule.hir).map_err(|_| {
                too_large(format!(
                    "expression too large: its NFA exceeds {} states",
                    self.nfa_limit
                ))
            })?;
        }
        let nfa = builder.build().map_err(|_| {
            too_large(format!(
                "expression too large: its NFA exceeds {} states",
                self.nfa_limit
            ))
        })?;

        let alphabet = Alphabet::new(
            &nfa.preds,
            &self.vocabulary,
            self.default_alphabet.then_some(self.profile),
        );
        let dfa = determinize(&nfa, &alphabet.classes, self.state_limit)
            .map_err(|_| {
                too_large(format!(
                    "the automaton exceeds the state limit of {} DFA states: simplify the expression or raise the limit",
                    self.state_limit
                ))
            })?;
        let dfa_states = dfa.len();
        let min = if self.minimize { minimize(&dfa) } else { dfa };
        let stats = Stats {
            nfa_states: nfa.states.len(),
            predicates: nfa.preds.len(),
            classes: alphabet.classes.len(),
            dfa_states,
            min_dfa_states: min.len(),
        };
        let warnings = self.warnings(&nfa);
        Ok(Automaton::from_dfa(
            min,
            alphabet,
            nfa,
            self.rules.clone(),
            warnings,
            stats,
        ))
    }

    fn warnings(&self, nfa: &Nfa) -> Vec<Warning> {
        let mut out = Vec::new();
        for (i, rule) in self.rules.iter().enumerate() {
            let id = RuleId(i as u32);
            let alone = single_rule_nfa(&rule.hir);
            if !alone.rule_can_match(0) {
                out.push(Warning {
                    rule: id,
                    message: "this rule can never match: no event satisfies one of its parts"
                        .into(),
                });
            } else if !renderable(&rule.hir, !self.profile.emits) {
                if renderable(&rule.hir, 0) {
                    let missing: Vec<&str> = EventType::ALL
                        .iter()
                        .filter(|t| !self.profile.emits(**t) && **t != EventType::Camera)
                        .map(|t| type_name(*t))
                        .collect();
                    out.push(Warning {
                        rule: id,
                        message: format!(
                            "this rule needs a {} event, which this renderer never emits: it will stay black",
                            missing.join(" or ")
                        ),
                    });
                } else {
                    out.push(Warning {
                        rule: id,
                        message: "rendered paths start with the camera event C and have no other C: this rule never matches one (start it with C)".into(),
                    });
                }
            }
        }
        let _ = nfa;
        out
    }
}

fn single_rule_nfa(hir: &Hir) -> Nfa {
    let mut b = NfaBuilder::new(usize::MAX);
    let _ = b.add_rule(hir);
    b.build().unwrap_or_else(|_| unreachable!("no limit"))
}

/// How a warning names an event type.
fn type_name(t: EventType) -> &'static str {
    match t {
        EventType::Camera => "C (camera)",
        EventType::Reflect => "R (reflection)",
        EventType::Transmit => "T (transmission)",
        EventType::Volume => "V (volume)",
        EventType::Light => "L (light)",
        EventType::Emission => "O (emission)",
        EventType::Background => "B (background)",
    }
}

/// Can the rule match a path of the shape renderers produce: `C` first, no other `C`, and
/// no event of the types in `never` (a bit set)? A walk of the rule's NFA paired with a
/// flag "the first event is behind us".
fn renderable(hir: &Hir, never: u8) -> bool {
    let excluded = EventType::Camera.bit() | never;
    let nfa = single_rule_nfa(hir);
    let mut seen = vec![[false; 2]; nfa.states.len()];
    let mut stack = vec![(nfa.start, 0usize)];
    while let Some((s, after_first)) = stack.pop() {
        if std::mem::replace(&mut seen[s as usize][after_first], true) {
            continue;
        }
        match &nfa.states[s as usize] {
            NfaState::Split(next) => stack.extend(next.iter().map(|&n| (n, after_first))),
            NfaState::Event { pred, next } => {
                let p = &nfa.preds[*pred as usize];
                let ok = if after_first == 0 {
                    p.matches(&Event::camera())
                } else {
                    !p.without_types(excluded).is_empty()
                };
                if ok {
                    stack.push((*next, 1));
                }
            }
            NfaState::Match(_) if after_first == 1 => return true,
            NfaState::Match(_) => {}
        }
    }
    false
}

/// Event classes: the distinct signatures (which predicates hold) of the events the
/// automaton may see.
#[derive(Clone, Debug)]
struct Alphabet {
    words: usize,
    /// The class of each vocabulary event, in the order given.
    vocabulary: Vec<ClassId>,
    /// Signature bits of each class, `words` u64s per class.
    classes: Vec<Vec<u64>>,
    by_signature: HashMap<Vec<u64>, u32>,
}

impl Alphabet {
    /// `default_events`: the profile whose event types the default alphabet covers (None:
    /// the vocabulary alone).
    fn new(preds: &[Pred], vocabulary: &[Event], default_events: Option<Profile>) -> Alphabet {
        let words = preds.len().div_ceil(64).max(1);
        let mut a = Alphabet {
            words,
            vocabulary: Vec::new(),
            classes: Vec::new(),
            by_signature: HashMap::new(),
        };
        let mut labels: Vec<&str> = preds.iter().flat_map(|p| p.mentioned_labels()).collect();
        labels.sort_unstable();
        labels.dedup();
        let types = EventType::ALL
            .into_iter()
            .filter(|&ty| default_events.is_some_and(|p| p.emits(ty)));
        for ty in types {
            let scattering = matches!(ty, EventType::Reflect | EventType::Transmit);
            for scatter in all_scatters().filter(|s| s.is_some() == scattering) {
                a.insert(preds, &Event::new::<&str>(ty, scatter, []));
                for l in &labels {
                    a.insert(preds, &Event::new(ty, scatter, [*l]));
                }
            }
        }
        for e in vocabulary {
            let class = a.insert(preds, e);
            a.vocabulary.push(ClassId(class));
        }
        a
    }

    fn signature(&self, preds: &[Pred], e: &Event) -> Vec<u64> {
        let mut sig = vec![0u64; self.words];
        for (i, p) in preds.iter().enumerate() {
            if p.matches(e) {
                sig[i / 64] |= 1 << (i % 64);
            }
        }
        sig
    }

    /// Adds the event's class if it is new; returns its class.
    fn insert(&mut self, preds: &[Pred], e: &Event) -> u32 {
        let sig = self.signature(preds, e);
        if let Some(&class) = self.by_signature.get(&sig) {
            return class;
        }
        let class = self.classes.len() as u32;
        self.by_signature.insert(sig.clone(), class);
        self.classes.push(sig);
        class
    }
}

/// The immutable automaton: classify events once, then one table load per vertex.
///
/// ```
/// let mut c = lpe::Compiler::new();
/// let direct = c.add("lpe:C<RD>[<L.>O]").unwrap();
/// let a = c.compile().unwrap();
/// let path = lpe::parse_path("C<RD'floor'><L'key'>").unwrap();
/// let mut s = a.start();
/// for e in &path {
///     s = a.step(s, a.classify(e).unwrap());
/// }
/// assert_eq!(a.accepting(s), &[direct]);
/// ```
#[derive(Clone, Debug)]
pub struct Automaton {
    /// `table[state + class]`, states pre-multiplied by `stride`, a power of two (rows
    /// padded with the dead state) so that a state's row is a shift away.
    table: Vec<StateId>,
    stride: u32,
    /// log2(stride).
    shift: u32,
    classes: u32,
    start: StateId,
    /// States at or above this row accept at least one rule.
    first_accepting: u32,
    accept_offsets: Vec<u32>,
    accept_rules: Vec<RuleId>,
    alphabet: Alphabet,
    nfa: Nfa,
    rules: Vec<Rule>,
    warnings: Vec<Warning>,
    stats: Stats,
}

impl Automaton {
    fn from_dfa(
        dfa: crate::dfa::Dfa,
        alphabet: Alphabet,
        nfa: Nfa,
        rules: Vec<Rule>,
        warnings: Vec<Warning>,
        stats: Stats,
    ) -> Automaton {
        let n = dfa.len();
        let k = dfa.classes.max(1).next_power_of_two();
        // Order: dead (0), then non-accepting, then accepting, so one compare answers
        // "accepting?" and another "dead?".
        let mut order: Vec<usize> = (1..n).collect();
        order.sort_by_key(|&s| (!dfa.accept[s].is_empty(), s));
        order.insert(0, 0);
        let mut rank = vec![0u32; n];
        for (r, &s) in order.iter().enumerate() {
            rank[s] = r as u32;
        }
        let first_accepting = order
            .iter()
            .position(|&s| !dfa.accept[s].is_empty())
            .unwrap_or(n) as u32;
        let mut table = Vec::with_capacity(n * k);
        let mut accept_offsets = vec![0u32];
        let mut accept_rules = Vec::new();
        for &s in &order {
            for c in 0..dfa.classes {
                table.push(StateId(
                    rank[dfa.next[s * dfa.classes + c] as usize] * k as u32,
                ));
            }
            table.extend(std::iter::repeat_n(StateId(0), k - dfa.classes));
            accept_rules.extend(dfa.accept[s].iter().map(|&r| RuleId(r)));
            accept_offsets.push(accept_rules.len() as u32);
        }
        Automaton {
            table,
            stride: k as u32,
            shift: k.trailing_zeros(),
            classes: dfa.classes as u32,
            start: StateId(rank[dfa.start as usize] * k as u32),
            first_accepting: first_accepting * k as u32,
            accept_offsets,
            accept_rules,
            alphabet,
            nfa,
            rules,
            warnings,
            stats,
        }
    }

    /// The state before any event (the camera event is the first step).
    #[inline]
    pub fn start(&self) -> StateId {
        self.start
    }

    /// The class of an event, or `None` if the automaton was not built for events like it
    /// (add it to [`Compiler::vocabulary`]).
    pub fn classify(&self, event: &Event) -> Option<ClassId> {
        let sig = self.alphabet.signature(&self.nfa.preds, event);
        self.alphabet.by_signature.get(&sig).map(|&c| ClassId(c))
    }

    /// The class of each event given to [`Compiler::vocabulary`], in that order: a
    /// renderer that builds its vocabulary once classifies it without a lookup that
    /// could miss.
    pub fn vocabulary_classes(&self) -> &[ClassId] {
        &self.alphabet.vocabulary
    }

    /// Advances the path by one event: one table load.
    #[inline(always)]
    pub fn step(&self, state: StateId, class: ClassId) -> StateId {
        self.table[(state.0 + class.0) as usize]
    }

    /// A dense index of the state, `0..state_count()`, for per-state tables.
    #[inline(always)]
    pub fn state_index(&self, state: StateId) -> usize {
        (state.0 >> self.shift) as usize
    }

    /// True if no rule can match any continuation: the path can stop.
    #[inline(always)]
    pub fn is_dead(&self, state: StateId) -> bool {
        state.0 == 0
    }

    /// The rules that accept a path ending in this state.
    #[inline]
    pub fn accepting(&self, state: StateId) -> &[RuleId] {
        if state.0 < self.first_accepting {
            return &[];
        }
        let row = (state.0 >> self.shift) as usize;
        &self.accept_rules[self.accept_offsets[row] as usize..self.accept_offsets[row + 1] as usize]
    }

    /// Runs a whole path; `None` if one of its events cannot be classified.
    pub fn run(&self, path: &[Event]) -> Option<&[RuleId]> {
        let mut s = self.start;
        for e in path {
            s = self.step(s, self.classify(e)?);
        }
        Some(self.accepting(s))
    }

    /// The reference answer by NFA simulation (for tests).
    pub fn simulate(&self, path: &[Event]) -> Vec<RuleId> {
        self.nfa.simulate(path).into_iter().map(RuleId).collect()
    }

    pub fn rules(&self) -> &[Rule] {
        &self.rules
    }

    pub fn rule(&self, id: RuleId) -> &Rule {
        &self.rules[id.0 as usize]
    }

    pub fn warnings(&self) -> &[Warning] {
        &self.warnings
    }

    pub fn stats(&self) -> Stats {
        self.stats
    }

    pub fn class_count(&self) -> usize {
        self.classes as usize
    }

    /// Every state of the automaton (for precomputing per-state facts at scene build).
    pub fn states(&self) -> impl Iterator<Item = StateId> + '_ {
        (0..self.state_count() as u32).map(move |i| StateId(i * self.stride))
    }

    pub fn state_count(&self) -> usize {
        self.table.len() / self.stride as usize
    }
}

/// Compiles definitions into one automaton with the default alphabet.
pub fn compile<S: AsRef<str>>(definitions: &[S]) -> Result<Automaton, Error> {
    let mut c = Compiler::new();
    for d in definitions {
        c.add(d.as_ref())?;
    }
    c.compile()
}

/// Does `definition` match `path`? Compiles with the path's events in the vocabulary.
pub fn matches(definition: &str, path: &[Event]) -> Result<bool, Error> {
    let mut c = Compiler::new();
    c.add(definition)?;
    c.vocabulary(path.iter().cloned());
    let a = c.compile()?;
    Ok(!a.run(path).unwrap_or(&[]).is_empty())
}
