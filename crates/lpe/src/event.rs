//! The event model of docs/lpe.md#paths-and-events: what a renderer feeds the automaton at each path vertex,
//! and the path notation of §10 used by tests and `lpe match`.

use crate::error::{Error, ErrorKind, Span};
use std::fmt;

/// What happened at a path vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum EventType {
    Camera,
    Reflect,
    Transmit,
    Light,
    Emission,
    Volume,
    Background,
}

impl EventType {
    pub const ALL: [EventType; 7] = [
        EventType::Camera,
        EventType::Reflect,
        EventType::Transmit,
        EventType::Light,
        EventType::Emission,
        EventType::Volume,
        EventType::Background,
    ];

    pub fn from_letter(c: char) -> Option<EventType> {
        Some(match c {
            'C' => EventType::Camera,
            'R' => EventType::Reflect,
            'T' => EventType::Transmit,
            'L' => EventType::Light,
            'O' => EventType::Emission,
            'V' => EventType::Volume,
            'B' => EventType::Background,
            _ => return None,
        })
    }

    pub fn letter(self) -> char {
        match self {
            EventType::Camera => 'C',
            EventType::Reflect => 'R',
            EventType::Transmit => 'T',
            EventType::Light => 'L',
            EventType::Emission => 'O',
            EventType::Volume => 'V',
            EventType::Background => 'B',
        }
    }

    pub(crate) fn bit(self) -> u8 {
        1 << (self as u8)
    }

    pub fn describe(self) -> &'static str {
        match self {
            EventType::Camera => "the camera",
            EventType::Reflect => "a reflection",
            EventType::Transmit => "a transmission",
            EventType::Light => "a light",
            EventType::Emission => "emission",
            EventType::Volume => "a volume event",
            EventType::Background => "the background",
        }
    }
}

/// The class of the lobe that scattered: diffuse, specular (glossy and mirror alike) or a
/// user data lobe.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ScatterClass {
    Diffuse,
    Specular,
    User,
}

impl ScatterClass {
    pub fn letter(self) -> char {
        match self {
            ScatterClass::Diffuse => 'D',
            ScatterClass::Specular => 'S',
            ScatterClass::User => 'U',
        }
    }

    /// Highest lobe number RenderMan allows for this class.
    pub fn max_lobe(self) -> u8 {
        match self {
            ScatterClass::User => 15,
            _ => 9,
        }
    }

    /// First bit of this class in the 37-bit scatter alphabet (bit 0 is *none*).
    fn base_bit(self) -> u32 {
        match self {
            ScatterClass::Diffuse => 1,
            ScatterClass::Specular => 11,
            ScatterClass::User => 21,
        }
    }
}

/// The lobe an event scattered through. `lobe == 0` means unnumbered.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Scatter {
    pub class: ScatterClass,
    pub lobe: u8,
}

impl Scatter {
    pub const fn new(class: ScatterClass, lobe: u8) -> Scatter {
        Scatter { class, lobe }
    }
    pub const fn diffuse(lobe: u8) -> Scatter {
        Scatter::new(ScatterClass::Diffuse, lobe)
    }
    pub const fn specular(lobe: u8) -> Scatter {
        Scatter::new(ScatterClass::Specular, lobe)
    }
    pub const fn user(lobe: u8) -> Scatter {
        Scatter::new(ScatterClass::User, lobe)
    }
}

impl fmt::Display for Scatter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.class.letter())?;
        if self.lobe > 0 {
            write!(f, "{}", self.lobe)?;
        }
        Ok(())
    }
}

/// Bit index of a concrete scatter in the scatter alphabet: 0 = none, then D0..D9,
/// S0..S9, U0..U15 (0 = unnumbered).
pub(crate) fn scatter_bit(scatter: Option<Scatter>) -> u32 {
    match scatter {
        None => 0,
        Some(s) => s.class.base_bit() + s.lobe as u32,
    }
}

pub(crate) const SCATTER_BITS: u32 = 37;
pub(crate) const ALL_SCATTERS: u64 = (1u64 << SCATTER_BITS) - 1;

/// Every concrete scatter value, in bit order (for building the default alphabet).
pub(crate) fn all_scatters() -> impl Iterator<Item = Option<Scatter>> {
    std::iter::once(None)
        .chain((0..=9).map(|l| Some(Scatter::diffuse(l))))
        .chain((0..=9).map(|l| Some(Scatter::specular(l))))
        .chain((0..=15).map(|l| Some(Scatter::user(l))))
}

/// Mask of all lobes of a class, any number.
pub(crate) fn class_mask(class: ScatterClass) -> u64 {
    let n = class.max_lobe() as u32 + 1;
    ((1u64 << n) - 1) << class.base_bit()
}

/// One vertex of a light path: type, scatter and the set of labels.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Event {
    pub ty: EventType,
    pub scatter: Option<Scatter>,
    /// Sorted and deduplicated: labels are a set.
    labels: Vec<String>,
}

impl Event {
    pub fn new<S: Into<String>>(
        ty: EventType,
        scatter: Option<Scatter>,
        labels: impl IntoIterator<Item = S>,
    ) -> Event {
        let mut labels: Vec<String> = labels.into_iter().map(Into::into).collect();
        labels.sort();
        labels.dedup();
        Event {
            ty,
            scatter,
            labels,
        }
    }

    /// An event with no scatter and no labels (`C`, `L`, `O`).
    pub fn bare(ty: EventType) -> Event {
        Event {
            ty,
            scatter: None,
            labels: Vec::new(),
        }
    }

    pub fn camera() -> Event {
        Event::bare(EventType::Camera)
    }

    pub fn labels(&self) -> &[String] {
        &self.labels
    }

    pub fn has_label(&self, label: &str) -> bool {
        self.labels
            .binary_search_by(|l| l.as_str().cmp(label))
            .is_ok()
    }
}

impl fmt::Display for Event {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.scatter.is_none() && self.labels.is_empty() {
            return write!(f, "{}", self.ty.letter());
        }
        write!(f, "<{}", self.ty.letter())?;
        match self.scatter {
            Some(s) => write!(f, "{s}")?,
            None if !self.labels.is_empty() => {}
            None => write!(f, "x")?,
        }
        for l in &self.labels {
            write!(f, "'{l}'")?;
        }
        write!(f, ">")
    }
}

/// Writes a path in the notation of docs/lpe.md#path-notation.
pub fn format_path(events: &[Event]) -> String {
    events.iter().map(|e| e.to_string()).collect()
}

/// Parses a concrete path in the notation of docs/lpe.md#path-notation, e.g. `C<RD'floor'><L'key'>`.
pub fn parse_path(src: &str) -> Result<Vec<Event>, Error> {
    let mut events = Vec::new();
    let mut chars = Cursor { src, pos: 0 };
    loop {
        chars.skip_ws();
        let Some((at, c)) = chars.peek() else { break };
        if let Some(ty) = EventType::from_letter(c) {
            chars.bump();
            events.push(Event::bare(ty));
        } else if c == '<' {
            chars.bump();
            events.push(parse_path_event(&mut chars, at)?);
        } else {
            return Err(chars.unexpected(at, "an event letter (C R T L O V B) or '<'"));
        }
    }
    if events.is_empty() {
        return Err(Error::new(
            ErrorKind::Empty,
            Span::at(src.len()),
            "empty path: expected at least the camera event C",
        ));
    }
    Ok(events)
}

fn parse_path_event(c: &mut Cursor<'_>, open: usize) -> Result<Event, Error> {
    c.skip_ws();
    let Some((at, ch)) = c.peek() else {
        return Err(c.unclosed(open));
    };
    let ty = EventType::from_letter(ch)
        .ok_or_else(|| c.unexpected(at, "an event type letter (C R T L O V B)"))?;
    c.bump();
    c.skip_ws();
    let mut scatter = None;
    if let Some((at, ch)) = c.peek() {
        let class = match ch {
            'D' => Some(ScatterClass::Diffuse),
            'S' | 'G' => Some(ScatterClass::Specular),
            'U' => Some(ScatterClass::User),
            'x' => {
                c.bump();
                None
            }
            _ => None,
        };
        if let Some(class) = class {
            c.bump();
            let digits_start = c.pos;
            while matches!(c.peek(), Some((_, d)) if d.is_ascii_digit()) {
                c.bump();
            }
            let digits = &c.src[digits_start..c.pos];
            let lobe = lobe_number(class, digits)
                .ok_or_else(|| lobe_error(Span::new(at, c.pos), class, digits))?;
            scatter = Some(Scatter::new(class, lobe));
        }
    }
    let mut labels = Vec::new();
    loop {
        c.skip_ws();
        match c.peek() {
            None => return Err(c.unclosed(open)),
            Some((_, '>')) => {
                c.bump();
                break;
            }
            Some((q, '\'')) => {
                let (label, end) = read_label(c.src, q)?;
                labels.push(label.to_string());
                c.pos = end;
            }
            Some((at, _)) => return Err(c.unexpected(at, "a label 'name' or '>'")),
        }
    }
    Ok(Event::new(ty, scatter, labels))
}

/// Reads the lobe number written after a scatter letter: empty = unnumbered; no leading
/// zero; within the class's range.
pub(crate) fn lobe_number(class: ScatterClass, digits: &str) -> Option<u8> {
    if digits.is_empty() {
        return Some(0);
    }
    if digits.starts_with('0') || digits.len() > 2 {
        return None;
    }
    let n: u8 = digits.parse().ok()?;
    (1..=class.max_lobe()).contains(&n).then_some(n)
}

pub(crate) fn lobe_error(span: Span, class: ScatterClass, digits: &str) -> Error {
    let why = if digits.starts_with('0') {
        "lobe numbers have no leading zero and start at 1".to_string()
    } else {
        format!("expected a lobe number from 1 to {}", class.max_lobe())
    };
    Error::new(
        ErrorKind::LobeRange,
        span,
        format!("lobe out of range: {why}"),
    )
}

/// Reads a quoted label starting at the quote `q`; returns the label text and the offset
/// just past the closing quote.
pub(crate) fn read_label(src: &str, q: usize) -> Result<(&str, usize), Error> {
    match src[q + 1..].find('\'') {
        Some(len) => Ok((&src[q + 1..q + 1 + len], q + 2 + len)),
        None => Err(Error::new(
            ErrorKind::UnterminatedLabel,
            Span::new(q, src.len()),
            "unterminated label: expected a closing quote '",
        )),
    }
}

/// A character cursor with byte offsets, shared by the path and expression parsers.
pub(crate) struct Cursor<'a> {
    pub src: &'a str,
    pub pos: usize,
}

impl<'a> Cursor<'a> {
    pub fn peek(&self) -> Option<(usize, char)> {
        self.src[self.pos..].chars().next().map(|c| (self.pos, c))
    }
    pub fn peek2(&self) -> Option<char> {
        let mut it = self.src[self.pos..].chars();
        it.next();
        it.next()
    }
    pub fn bump(&mut self) {
        if let Some(c) = self.src[self.pos..].chars().next() {
            self.pos += c.len_utf8();
        }
    }
    pub fn skip_ws(&mut self) {
        while let Some((_, c)) = self.peek() {
            if matches!(c, ' ' | '\t' | '\r' | '\n') {
                self.bump();
            } else {
                break;
            }
        }
    }
    pub fn at_end(&self) -> bool {
        self.pos >= self.src.len()
    }
    /// The span of the token starting at `at`: a label, `[^`, a numbered symbol, or one
    /// character.
    pub fn token_span(&self, at: usize) -> Span {
        let rest = &self.src[at..];
        let mut it = rest.chars();
        let Some(c) = it.next() else {
            return Span::at(at);
        };
        if c == '\'' {
            if let Some(len) = rest[1..].find('\'') {
                return Span::new(at, at + len + 2);
            }
        }
        if rest.starts_with("[^") {
            return Span::new(at, at + 2);
        }
        if matches!(c, 'D' | 'S' | 'G' | 'U') {
            let digits = rest[1..].bytes().take_while(u8::is_ascii_digit).count();
            return Span::new(at, at + 1 + digits);
        }
        Span::new(at, at + c.len_utf8())
    }
    pub fn unexpected(&self, at: usize, expected: &str) -> Error {
        let span = self.token_span(at);
        let found = &self.src[span.start..span.end];
        let err = Error::new(
            ErrorKind::Unexpected,
            span,
            format!("unexpected {}: expected {expected}", quote_token(found)),
        );
        // The digit for the letter: guides write `[<L.>0]` where `O` (object) is meant.
        if found == "0" {
            err.with_help("did you mean 'O' (the letter, an object's emission)?")
        } else {
            err
        }
    }
    pub fn unclosed(&self, open: usize) -> Error {
        let opener = self.src[open..].chars().next().unwrap_or('?');
        let closer = match opener {
            '<' => '>',
            '(' => ')',
            '[' => ']',
            '{' => '}',
            _ => '?',
        };
        let what = match opener {
            '<' => "event",
            '(' => "group",
            '[' => "set",
            _ => "bracket",
        };
        Error::new(
            ErrorKind::Unclosed,
            Span::at(self.src.len()),
            format!("expected '{closer}' to close the {what} opened at {open}"),
        )
    }
}

pub(crate) fn quote_token(tok: &str) -> String {
    if tok.starts_with('\'') {
        format!("label {tok}")
    } else {
        format!("'{}'", tok.escape_debug())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_examples_of_the_contract() {
        let p = parse_path("C<RD'floor'><RS2'ball'><L'key'>").unwrap();
        assert_eq!(p.len(), 4);
        assert_eq!(p[1].scatter, Some(Scatter::diffuse(0)));
        assert!(p[1].has_label("floor"));
        assert_eq!(p[2].scatter, Some(Scatter::specular(2)));
        assert_eq!(p[3].ty, EventType::Light);
        let p = parse_path("C <R D4 'b'> <Lx'key'> <T S>").unwrap();
        assert_eq!(p[1].scatter, Some(Scatter::diffuse(4)));
        assert_eq!(p[2].scatter, None);
        assert_eq!(p[3].scatter, Some(Scatter::specular(0)));
    }

    #[test]
    fn path_round_trips_through_display() {
        let src = "C<RD'a''b'><TS8'glass'><RU2>L<Lx'key'>O";
        let p = parse_path(src).unwrap();
        assert_eq!(parse_path(&format_path(&p)).unwrap(), p);
    }

    #[test]
    fn path_errors_point_at_the_problem() {
        assert_eq!(parse_path("C<RD").unwrap_err().span, Span::at(4));
        assert_eq!(parse_path("C<RD10>").unwrap_err().span, Span::new(3, 6));
        assert_eq!(parse_path("CQ").unwrap_err().span, Span::new(1, 2));
        assert_eq!(parse_path("").unwrap_err().kind, ErrorKind::Empty);
    }
}
