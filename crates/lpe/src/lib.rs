//! # lpe — Light Path Expressions
//!
//! The language of `shared/LPE.md`, compiled to one minimal DFA for all AOVs. The
//! pipeline is the module tree: [`syntax`] (parse, print) → [`hir`] (event predicates)
//! → [`nfa`] (Thompson, one pattern per rule) → [`dfa`] (subset construction over event
//! classes, Hopcroft minimisation) → [`Automaton`] (classify once, one table load per
//! vertex).
//!
//! ```
//! let mut compiler = lpe::Compiler::new();
//! let beauty = compiler.add("lpe:beauty").unwrap();
//! let key = compiler.add("key = C<.>*[<L.'key'>O]").unwrap();
//! let automaton = compiler.compile().unwrap();
//! let path = lpe::parse_path("C<RD'floor'><L'key'>").unwrap();
//! assert_eq!(automaton.run(&path), Some(&[beauty, key][..]));
//! ```

pub mod dfa;
mod error;
mod event;
pub mod explain;
pub mod hir;
pub mod nfa;
mod prefix;
mod runtime;
pub mod syntax;

#[cfg(feature = "miette")]
pub use error::Report;
pub use error::{Error, ErrorKind, Span};
pub use event::{format_path, parse_path, Event, EventType, Scatter, ScatterClass};
pub use prefix::{standard_name, Flags, Prefix, BEAUTY_PARTITION, STANDARD_NAMES, STANDARD_SUMS};
pub use runtime::{
    compile, matches, Automaton, ClassId, Compiler, Profile, Rule, RuleId, StateId, Stats, Warning,
    DEFAULT_STATE_LIMIT,
};
