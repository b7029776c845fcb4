//! Diagnostics: every error has a kind, a byte span into the source and a sentence that
//! says what was expected. `render` draws a caret under the span.

use std::fmt;

/// A byte range into the source text, end exclusive.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Span {
    pub start: usize,
    pub end: usize,
}

impl Span {
    pub fn new(start: usize, end: usize) -> Span {
        Span { start, end }
    }
    /// An empty span at one offset (end of input, or an insertion point).
    pub fn at(offset: usize) -> Span {
        Span {
            start: offset,
            end: offset,
        }
    }
}

/// The kinds of error; their `name()`s are the `kind` field of the conformance vectors.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ErrorKind {
    Unexpected,
    Unclosed,
    UnknownPrefix,
    DuplicatePrefix,
    QuantifierInEvent,
    QuantifierValue,
    QuantifierSyntax,
    QuantifierPosition,
    DoubleQuantifier,
    Empty,
    MixedSlots,
    SetMember,
    BarPosition,
    SlotKind,
    LobeRange,
    UnterminatedLabel,
    /// Groups and sets nested deeper than the parser's limit (`MAX_NESTING`).
    Nesting,
    /// The automaton would exceed the configured state limit.
    StateLimit,
    /// The path's events are not in the vocabulary the automaton was built for.
    UnknownEvent,
}

impl ErrorKind {
    pub fn name(self) -> &'static str {
        match self {
            ErrorKind::Unexpected => "unexpected",
            ErrorKind::Unclosed => "unclosed",
            ErrorKind::UnknownPrefix => "unknown_prefix",
            ErrorKind::DuplicatePrefix => "duplicate_prefix",
            ErrorKind::QuantifierInEvent => "quantifier_in_event",
            ErrorKind::QuantifierValue => "quantifier_value",
            ErrorKind::QuantifierSyntax => "quantifier_syntax",
            ErrorKind::QuantifierPosition => "quantifier_position",
            ErrorKind::DoubleQuantifier => "double_quantifier",
            ErrorKind::Empty => "empty",
            ErrorKind::MixedSlots => "mixed_slots",
            ErrorKind::SetMember => "set_member",
            ErrorKind::BarPosition => "bar_position",
            ErrorKind::SlotKind => "slot_kind",
            ErrorKind::LobeRange => "lobe_range",
            ErrorKind::UnterminatedLabel => "unterminated_label",
            ErrorKind::Nesting => "nesting",
            ErrorKind::StateLimit => "state_limit",
            ErrorKind::UnknownEvent => "unknown_event",
        }
    }
}

/// An error in an LPE definition (or a path), located in its source.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{message}")]
pub struct Error {
    pub kind: ErrorKind,
    pub span: Span,
    pub message: String,
    /// An optional suggestion, shown under the caret ("did you mean `<.D>`?").
    pub help: Option<String>,
}

impl Error {
    pub fn new(kind: ErrorKind, span: Span, message: impl Into<String>) -> Error {
        Error {
            kind,
            span,
            message: message.into(),
            help: None,
        }
    }

    pub fn with_help(mut self, help: impl Into<String>) -> Error {
        self.help = Some(help.into());
        self
    }

    /// The error as a terminal diagnostic: the source line with a caret under the span.
    ///
    /// ```text
    /// error: unknown prefix 'unocluded'
    ///   |
    ///   | unocluded;C<RD>L
    ///   | ^^^^^^^^^
    ///   = help: did you mean 'unoccluded'?
    /// ```
    pub fn render(&self, source: &str) -> String {
        let mut out = format!("error[{}]: {}\n", self.kind.name(), self.message);
        // Show the line holding the span start; columns count characters, not bytes.
        let start = self.span.start.min(source.len());
        let line_start = source[..start].rfind('\n').map_or(0, |i| i + 1);
        let line_end = source[start..]
            .find('\n')
            .map_or(source.len(), |i| start + i);
        let line = &source[line_start..line_end];
        let col = source[line_start..start].chars().count();
        let end = self.span.end.clamp(start, line_end);
        let width = source[start..end].chars().count().max(1);
        let shown: String = line
            .chars()
            .map(|c| if c == '\t' { ' ' } else { c })
            .collect();
        out.push_str("  |\n");
        out.push_str(&format!("  | {shown}\n"));
        out.push_str(&format!("  | {}{}\n", " ".repeat(col), "^".repeat(width)));
        if let Some(help) = &self.help {
            out.push_str(&format!("  = help: {help}\n"));
        }
        out
    }
}

impl fmt::Display for Span {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}..{}", self.start, self.end)
    }
}

#[cfg(feature = "miette")]
mod miette_impl {
    use super::Error;

    /// An [`Error`] together with its source, for `miette`'s fancy reports.
    #[derive(Debug, thiserror::Error)]
    #[error("{}", error.message)]
    pub struct Report {
        pub error: Error,
        pub text: String,
    }

    impl miette::Diagnostic for Report {
        fn code<'a>(&'a self) -> Option<Box<dyn std::fmt::Display + 'a>> {
            Some(Box::new(format!("lpe::{}", self.error.kind.name())))
        }
        fn help<'a>(&'a self) -> Option<Box<dyn std::fmt::Display + 'a>> {
            self.error
                .help
                .as_ref()
                .map(|h| Box::new(h) as Box<dyn std::fmt::Display>)
        }
        fn source_code(&self) -> Option<&dyn miette::SourceCode> {
            Some(&self.text)
        }
        fn labels(&self) -> Option<Box<dyn Iterator<Item = miette::LabeledSpan> + '_>> {
            let s = self.error.span;
            Some(Box::new(std::iter::once(miette::LabeledSpan::at(
                s.start..s.end,
                "here",
            ))))
        }
    }
}

#[cfg(feature = "miette")]
pub use miette_impl::Report;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn caret_sits_under_the_span() {
        let e = Error::new(ErrorKind::UnknownPrefix, Span::new(0, 9), "unknown prefix")
            .with_help("did you mean 'unoccluded'?");
        let r = e.render("unocluded;C<RD>L");
        assert!(r.contains("  | unocluded;C<RD>L\n  | ^^^^^^^^^\n"), "{r}");
        assert!(r.contains("help: did you mean"));
        let e = Error::new(ErrorKind::Unclosed, Span::at(4), "expected '>'");
        assert!(e.render("C<RD").contains("  |     ^\n"));
    }
}
