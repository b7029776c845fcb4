//! Text to syntax tree and back: the parser (with byte-span diagnostics) and the printer.

pub mod ast;
mod parser;
mod print;

pub use parser::{parse_definition, MAX_NESTING};
pub use print::print_definition;
