//! Property tests: the DFA agrees with the NFA simulator, minimisation changes no answer,
//! printing round-trips, and no input makes the compiler panic.

use lpe::{Compiler, Event, EventType, Scatter};
use proptest::prelude::*;

const ATOMS: &[&str] = &[
    "C",
    "R",
    "T",
    "L",
    "O",
    "V",
    "D",
    "S",
    "G",
    "U",
    "D2",
    "S8",
    "U2",
    "U6",
    "'a'",
    "'key'",
    ".",
    "<RD>",
    "<L.'key'>",
    "<.[^D2 D3]>",
    "[DS]",
    "[^'a']",
    "[^R]",
    "[^D]",
    "<[RT]S'a'>",
    "<L'key''b'>",
    "<Lx>",
    "<.x>",
    "<R(D|S)'b'>",
    "<..[^'a' 'b']>",
    "[<L.>O]",
    "<TS8>",
    "<'b'>",
    "<L.('key'|'fill')>",
];
const QUANTIFIERS: &[&str] = &[
    "", "", "", "*", "+", "?", "{2}", "{1,2}", "{,2}", "{2,}", "{0,3}",
];

fn expr() -> impl Strategy<Value = String> {
    let unit = (
        prop::sample::select(ATOMS),
        prop::sample::select(QUANTIFIERS),
    )
        .prop_map(|(a, q)| format!("{a}{q}"));
    let leaf = prop::collection::vec(unit, 1..4).prop_map(|v| v.concat());
    leaf.prop_recursive(3, 24, 4, |inner| {
        prop_oneof![
            prop::collection::vec(inner.clone(), 1..4).prop_map(|v| v.concat()),
            (inner.clone(), prop::sample::select(QUANTIFIERS))
                .prop_map(|(e, q)| format!("({e}){q}")),
            (inner.clone(), inner.clone()).prop_map(|(a, b)| format!("({a})|({b})")),
            prop::collection::vec(inner, 1..3).prop_map(|v| format!(
                "[{}]",
                v.iter().map(|e| format!("({e})")).collect::<String>()
            )),
        ]
    })
}

fn event() -> impl Strategy<Value = Event> {
    let ty = prop::sample::select(EventType::ALL.to_vec());
    let scatter = prop_oneof![
        Just(None),
        (0u8..=3).prop_map(|n| Some(Scatter::diffuse(n))),
        prop::sample::select(vec![0u8, 2, 8]).prop_map(|n| Some(Scatter::specular(n))),
        prop::sample::select(vec![0u8, 2, 6]).prop_map(|n| Some(Scatter::user(n))),
    ];
    let labels = prop::collection::vec(
        prop::sample::select(vec!["a", "b", "key", "fill", "floor"]),
        0..3,
    );
    (ty, scatter, labels).prop_map(|(t, s, l)| Event::new(t, s, l))
}

fn path() -> impl Strategy<Value = Vec<Event>> {
    prop::collection::vec(event(), 0..7).prop_map(|mut v| {
        v.insert(0, Event::camera());
        v
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 192, ..ProptestConfig::default() })]

    #[test]
    fn dfa_agrees_with_nfa_and_minimisation_changes_nothing(
        exprs in prop::collection::vec(expr(), 1..4),
        paths in prop::collection::vec(path(), 1..12),
    ) {
        let build = |minimize: bool| {
            let mut c = Compiler::new().minimize(minimize);
            for e in &exprs {
                c.add(e).unwrap();
            }
            c.vocabulary(paths.iter().flatten().cloned());
            c.compile()
        };
        let (Ok(min), Ok(full)) = (build(true), build(false)) else {
            // Only the state limit may refuse a valid expression.
            return Ok(());
        };
        prop_assert!(min.state_count() <= full.state_count());
        for p in &paths {
            let dfa = min.run(p).unwrap().to_vec();
            prop_assert_eq!(&dfa, &min.simulate(p), "{:?} on {}", exprs, lpe::format_path(p));
            prop_assert_eq!(&dfa, &full.run(p).unwrap().to_vec());
        }
    }

    #[test]
    fn printing_round_trips(e in expr()) {
        let def = lpe::syntax::parse_definition(&e).unwrap();
        let printed = lpe::syntax::print_definition(&def);
        let again = lpe::syntax::parse_definition(&printed).unwrap();
        prop_assert_eq!(lpe::syntax::print_definition(&again), printed);
    }

    #[test]
    fn arbitrary_text_never_panics(s in "[CRTLOVBDSGUx.<>\\[\\]()|*+?{},^;:=' 0-9a-z\\t\\n]{0,40}") {
        if let Err(e) = lpe::compile(&[&s]) {
            prop_assert!(e.span.start <= e.span.end && e.span.end <= s.len());
            prop_assert!(!e.message.is_empty());
            let _ = e.render(&s);
        }
    }

    #[test]
    fn any_unicode_never_panics(s in "\\PC{0,30}") {
        if let Err(e) = lpe::compile(&[&s]) {
            prop_assert!(s.is_char_boundary(e.span.start) && s.is_char_boundary(e.span.end));
            let _ = e.render(&s);
        }
        let _ = lpe::parse_path(&s);
    }

    #[test]
    fn mutated_expressions_never_panic(e in expr(), at in any::<prop::sample::Index>(), c in prop::sample::select(vec!['<', '>', '[', ']', '(', ')', '\'', '{', '}', '|', '*', '^', 'x', ' '])) {
        let mut s: Vec<char> = e.chars().collect();
        let i = at.index(s.len() + 1);
        s.insert(i, c);
        let s: String = s.into_iter().collect();
        let _ = lpe::compile(&[&s]);
    }
}

#[test]
fn huge_repetitions_are_an_error_not_a_hang() {
    for src in [
        "((((D{64}){64}){64}){64})",
        "C(.{1,64}){64}(.{1,64}){64}L",
        "C(['a' 'b']{1,64}['b' 'c']{1,64}){1,64}",
    ] {
        let Err(e) = lpe::compile(&[src]) else {
            panic!("{src} compiled")
        };
        assert_eq!(e.kind, lpe::ErrorKind::StateLimit, "{src}: {}", e.message);
        assert_eq!((e.span.start, e.span.end), (0, src.len()));
    }
}

#[test]
fn state_limit_is_configurable() {
    let mut c = Compiler::new().state_limit(5);
    c.add("C[DS]{10}L").unwrap();
    let Err(e) = c.compile() else {
        panic!("compiled within 5 states")
    };
    assert_eq!(e.kind, lpe::ErrorKind::StateLimit);
}
