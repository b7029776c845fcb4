//! A hand-written recursive-descent parser over characters, so that every error can
//! point at exactly the token docs/lpe.md#errors names.

use super::ast::{Body, Definition, Expr, Item, Slot, SlotItem, SlotKind};
use crate::error::{Error, ErrorKind, Span};
use crate::event::{lobe_error, lobe_number, read_label, Cursor, EventType, ScatterClass};
use crate::prefix::{closest, standard_name, Prefix, STANDARD_NAMES};

/// Parses one AOV definition: `[NAME =] [lpe:] {PREFIX ;} expression`.
pub fn parse_definition(src: &str) -> Result<Definition, Error> {
    let mut p = Parser {
        c: Cursor { src, pos: 0 },
        depth: 0,
    };
    let name = p.name();
    p.c.skip_ws();
    let lpe_marker = p.c.src[p.c.pos..].starts_with("lpe:");
    if lpe_marker {
        p.c.pos += 4;
    }
    let prefixes = p.prefixes()?;
    p.c.skip_ws();
    let rest = src[p.c.pos..].trim_end();
    if lpe_marker {
        if let Some((canonical, _)) = standard_name(rest) {
            return Ok(Definition {
                name,
                lpe_marker,
                prefixes,
                body: Body::Standard(canonical),
            });
        }
    }
    if p.c.at_end() {
        return Err(Error::new(
            ErrorKind::Empty,
            Span::at(src.len()),
            "empty expression: expected an expression such as C<RD>[<L.>O]",
        ));
    }
    let expr = p
        .sequence()
        .map_err(|e| suggest_standard_name(e, rest, lpe_marker))?;
    p.c.skip_ws();
    if let Some((at, _)) = p.c.peek() {
        return Err(suggest_standard_name(
            p.c.unexpected(at, "an event, '(' , '[', '<' or the end of the expression"),
            rest,
            lpe_marker,
        ));
    }
    Ok(Definition {
        name,
        lpe_marker,
        prefixes,
        body: Body::Expr(expr),
    })
}

/// A word that is almost a standard name gets a hint on top of its syntax error.
fn suggest_standard_name(err: Error, rest: &str, lpe_marker: bool) -> Error {
    if err.help.is_some() || rest.is_empty() || !rest.chars().all(|c| c.is_ascii_alphabetic()) {
        return err;
    }
    if let Some((name, _)) = standard_name(rest) {
        return err.with_help(format!(
            "standard names need the lpe: marker: write 'lpe:{name}'"
        ));
    }
    if let Some(name) = closest(rest, STANDARD_NAMES.iter().map(|(n, _)| *n)) {
        let marker = if lpe_marker { "" } else { "lpe:" };
        return err.with_help(format!(
            "did you mean the standard name '{marker}{name}'? (exact or all-lowercase spelling)"
        ));
    }
    err
}

struct Parser<'a> {
    c: Cursor<'a>,
    /// Groups and sets open around the cursor.
    depth: u32,
}

/// Groups and sets nested deeper than this are an error: every pass over the tree (parse,
/// lowering, printing, dropping) recurses once per level, and 8000 levels overflowed the
/// stack. Real expressions nest a handful of levels.
pub const MAX_NESTING: u32 = 100;

fn is_ident_start(c: char) -> bool {
    c.is_ascii_alphabetic() || c == '_'
}
fn is_ident_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

fn is_atom_start(c: char) -> bool {
    matches!(
        c,
        '(' | '['
            | '<'
            | '.'
            | '\''
            | 'C'
            | 'R'
            | 'T'
            | 'L'
            | 'O'
            | 'V'
            | 'B'
            | 'D'
            | 'S'
            | 'G'
            | 'U'
    )
}

fn is_quantifier_start(c: char) -> bool {
    matches!(c, '*' | '+' | '?' | '{')
}

/// Quantifier bounds above this are errors (docs/lpe.md#quantifiers).
const MAX_BOUND: u64 = 64;

impl<'a> Parser<'a> {
    /// An identifier at the cursor (after whitespace), without consuming it.
    fn ident_at(&self, from: usize) -> Option<(usize, usize)> {
        let src = self.c.src;
        let start = from + src[from..].len()
            - src[from..]
                .trim_start_matches([' ', '\t', '\r', '\n'])
                .len();
        let mut chars = src[start..].char_indices();
        match chars.next() {
            Some((_, c)) if is_ident_start(c) => {}
            _ => return None,
        }
        let len = src[start..]
            .find(|c: char| !is_ident_char(c))
            .unwrap_or(src.len() - start);
        Some((start, start + len))
    }

    /// The next non-whitespace character from `from`.
    fn next_char(&self, from: usize) -> Option<(usize, char)> {
        self.c.src[from..]
            .char_indices()
            .find(|(_, c)| !matches!(c, ' ' | '\t' | '\r' | '\n'))
            .map(|(i, c)| (from + i, c))
    }

    /// `NAME =` at the start, if present.
    fn name(&mut self) -> Option<String> {
        let (start, end) = self.ident_at(self.c.pos)?;
        let (eq, c) = self.next_char(end)?;
        if c != '=' {
            return None;
        }
        self.c.pos = eq + 1;
        Some(self.c.src[start..end].to_string())
    }

    /// Every identifier followed by `;` is a prefix.
    fn prefixes(&mut self) -> Result<Vec<Prefix>, Error> {
        let mut prefixes = Vec::new();
        while let Some((start, end)) = self.ident_at(self.c.pos) {
            let Some((semi, ';')) = self.next_char(end) else {
                break;
            };
            let word = &self.c.src[start..end];
            let span = Span::new(start, end);
            let Some(prefix) = Prefix::from_word(word) else {
                let mut err = Error::new(
                    ErrorKind::UnknownPrefix,
                    span,
                    format!("unknown prefix '{word}': expected one of {}", prefix_list()),
                );
                if let Some((name, _)) = standard_name(word) {
                    err = err.with_help(format!(
                        "'{name}' is a standard name, not a prefix: write it alone after the prefixes, as 'lpe:{name}'"
                    ));
                } else if let Some(best) = closest(word, Prefix::ALL.map(Prefix::word)) {
                    err = err.with_help(format!("did you mean '{best}'?"));
                }
                return Err(err);
            };
            if prefixes.contains(&prefix) {
                return Err(Error::new(
                    ErrorKind::DuplicatePrefix,
                    span,
                    format!("prefix '{word}' is given twice: each prefix may appear at most once"),
                ));
            }
            prefixes.push(prefix);
            self.c.pos = semi + 1;
        }
        Ok(prefixes)
    }

    /// `sequence := alt { alt }`, up to the end of input or a `)`.
    fn sequence(&mut self) -> Result<Expr, Error> {
        let mut units = Vec::new();
        loop {
            self.c.skip_ws();
            let Some((at, c)) = self.c.peek() else { break };
            if c == ')' {
                break;
            }
            if c == '|' {
                return Err(Error::new(
                    ErrorKind::BarPosition,
                    Span::new(at, at + 1),
                    "'|' needs a unit before it: nothing to join here",
                ));
            }
            if is_quantifier_start(c) && units.is_empty() {
                return Err(Error::new(
                    ErrorKind::QuantifierPosition,
                    Span::new(at, at + 1),
                    "a quantifier needs something to repeat before it",
                ));
            }
            if !is_atom_start(c) {
                let mut err = self.c.unexpected(
                    at,
                    "an event: C R T L O V B D S U, '.', a 'label', '<', '(' or '['",
                );
                if c == 'x' {
                    err = err.with_help("'x' (no scatter) is only allowed in the scatter slot of an event, as in <Lx>");
                }
                return Err(err);
            }
            units.push(self.alternation()?);
        }
        Ok(if units.len() == 1 {
            units.pop().unwrap_or(Expr::Concat(Vec::new()))
        } else {
            Expr::Concat(units)
        })
    }

    /// `alt := unit { '|' unit }`.
    fn alternation(&mut self) -> Result<Expr, Error> {
        let first = self.unit()?;
        let mut arms = vec![first];
        loop {
            self.c.skip_ws();
            match self.c.peek() {
                Some((_, '|')) => {
                    self.c.bump();
                    self.c.skip_ws();
                    match self.c.peek() {
                        Some((_, c)) if is_atom_start(c) => {}
                        Some((at, _)) => {
                            let span = self.c.token_span(at);
                            return Err(Error::new(
                                ErrorKind::BarPosition,
                                span,
                                "expected an event after '|'",
                            ));
                        }
                        None => {
                            return Err(Error::new(
                                ErrorKind::BarPosition,
                                Span::at(self.c.src.len()),
                                "expected an event after '|', found the end of the expression",
                            ))
                        }
                    }
                    arms.push(self.unit()?);
                }
                _ if arms.len() == 1 => return Ok(arms.swap_remove(0)),
                _ => return Ok(Expr::Alt(arms)),
            }
        }
    }

    /// `unit := atom [quantifier]`.
    fn unit(&mut self) -> Result<Expr, Error> {
        let atom = self.atom()?;
        self.c.skip_ws();
        let Some((at, c)) = self.c.peek() else {
            return Ok(atom);
        };
        if !is_quantifier_start(c) {
            return Ok(atom);
        }
        let (min, max) = self.quantifier(at, c)?;
        self.c.skip_ws();
        if let Some((at2, c2)) = self.c.peek() {
            if is_quantifier_start(c2) {
                return Err(Error::new(
                    ErrorKind::DoubleQuantifier,
                    Span::new(at2, at2 + 1),
                    "only one quantifier per unit: group it first, as in (D*){2}",
                ));
            }
        }
        Ok(Expr::Repeat {
            expr: Box::new(atom),
            min,
            max,
        })
    }

    fn quantifier(&mut self, start: usize, c: char) -> Result<(u32, Option<u32>), Error> {
        self.c.bump();
        match c {
            '*' => return Ok((0, None)),
            '+' => return Ok((1, None)),
            '?' => return Ok((0, Some(1))),
            _ => {}
        }
        let syntax = |c: &Cursor<'_>, what: &str| -> Error {
            // A token (docs/lpe.md#errors): a numbered symbol such as `D4` or a label is reported
            // whole, as anywhere else.
            let span = match c.peek() {
                Some((at, _)) => c.token_span(at),
                None => Span::at(c.src.len()),
            };
            Error::new(
                ErrorKind::QuantifierSyntax,
                span,
                format!("malformed quantifier: expected {what}"),
            )
        };
        self.c.skip_ws();
        let n = self.number();
        self.c.skip_ws();
        let (n, m) = match self.c.peek() {
            Some((_, '}')) => match n {
                Some(n) => (n, Some(n)),
                None => return Err(syntax(&self.c, "a number in {n}, {n,}, {,m} or {n,m}")),
            },
            Some((_, ',')) => {
                self.c.bump();
                self.c.skip_ws();
                let m = self.number();
                self.c.skip_ws();
                match self.c.peek() {
                    Some((_, '}')) if n.is_none() && m.is_none() => {
                        return Err(syntax(&self.c, "a number in {n,}, {,m} or {n,m}"))
                    }
                    Some((_, '}')) => (n.unwrap_or(0), m),
                    _ => {
                        return Err(syntax(
                            &self.c,
                            if m.is_some() {
                                "'}'"
                            } else {
                                "a number or '}'"
                            },
                        ))
                    }
                }
            }
            _ => {
                return Err(syntax(
                    &self.c,
                    if n.is_some() {
                        "',' or '}'"
                    } else {
                        "a number"
                    },
                ));
            }
        };
        self.c.bump(); // '}'
        let span = Span::new(start, self.c.pos);
        let bad = |msg: String| Err(Error::new(ErrorKind::QuantifierValue, span, msg));
        if n > MAX_BOUND || m.is_some_and(|m| m > MAX_BOUND) {
            return bad(format!(
                "quantifier bound above {MAX_BOUND}: path depths never get that deep"
            ));
        }
        match m {
            Some(0) => bad(
                "quantifier allows zero repetitions only: the unit would match nothing; remove it"
                    .into(),
            ),
            Some(m) if n > m => bad(format!("quantifier minimum {n} is above its maximum {m}")),
            _ => Ok((n as u32, m.map(|m| m as u32))),
        }
    }

    /// Decimal digits read by value, saturating (the caller rejects anything above 64).
    fn number(&mut self) -> Option<u64> {
        let mut value: Option<u64> = None;
        while let Some((_, d)) = self.c.peek() {
            let Some(digit) = d.to_digit(10) else { break };
            value = Some(
                value
                    .unwrap_or(0)
                    .saturating_mul(10)
                    .saturating_add(digit as u64),
            );
            self.c.bump();
        }
        value
    }

    fn atom(&mut self) -> Result<Expr, Error> {
        let Some((at, c)) = self.c.peek() else {
            return Err(Error::new(
                ErrorKind::Unexpected,
                Span::at(self.c.src.len()),
                "expected an event",
            ));
        };
        match c {
            '(' => {
                self.c.bump();
                let inner = self.nested(at, Self::sequence)?;
                self.c.skip_ws();
                match self.c.peek() {
                    None => Err(self.c.unclosed(at)),
                    Some((close, _)) => {
                        if matches!(&inner, Expr::Concat(v) if v.is_empty()) {
                            return Err(Error::new(
                                ErrorKind::Empty,
                                Span::new(close, close + 1),
                                "empty group (): expected at least one event inside",
                            ));
                        }
                        self.c.bump();
                        Ok(Expr::Group(Box::new(inner)))
                    }
                }
            }
            '[' if self.c.peek2() == Some('^') => {
                self.c.pos += 2;
                self.negated_set(at)
            }
            '[' => {
                self.c.bump();
                self.nested(at, |p| p.set(at))
            }
            '<' => {
                self.c.bump();
                self.event(at)
            }
            '.' => {
                self.c.bump();
                Ok(Expr::Any)
            }
            _ => match self.item(at)? {
                Some(item) => Ok(Expr::Item(item)),
                None => Err(self.c.unexpected(at, "an event")),
            },
        }
    }

    /// Parses what a `(` or `[` at `open` holds, one level deeper.
    fn nested(
        &mut self,
        open: usize,
        inner: impl FnOnce(&mut Self) -> Result<Expr, Error>,
    ) -> Result<Expr, Error> {
        if self.depth >= MAX_NESTING {
            return Err(Error::new(
                ErrorKind::Nesting,
                Span::new(open, open + 1),
                format!(
                    "groups and sets nested more than {MAX_NESTING} deep: expected at most {MAX_NESTING} levels of '(' and '['"
                ),
            ));
        }
        self.depth += 1;
        let expr = inner(self);
        self.depth -= 1;
        expr
    }

    /// A symbol or label at `at`, consumed; `None` (nothing consumed) if there is none.
    fn item(&mut self, at: usize) -> Result<Option<Item>, Error> {
        let Some((_, c)) = self.c.peek() else {
            return Ok(None);
        };
        if c == '\'' {
            let (label, end) = read_label(self.c.src, at)?;
            self.c.pos = end;
            return Ok(Some(Item::Label(label.to_string())));
        }
        if let Some(ty) = EventType::from_letter(c) {
            self.c.bump();
            return Ok(Some(Item::Type(ty)));
        }
        let class = match c {
            'D' => ScatterClass::Diffuse,
            'S' | 'G' => ScatterClass::Specular,
            'U' => ScatterClass::User,
            _ => return Ok(None),
        };
        self.c.bump();
        let digits_start = self.c.pos;
        while matches!(self.c.peek(), Some((_, d)) if d.is_ascii_digit()) {
            self.c.bump();
        }
        let digits = &self.c.src[digits_start..self.c.pos];
        let lobe = lobe_number(class, digits)
            .ok_or_else(|| lobe_error(Span::new(at, self.c.pos), class, digits))?;
        Ok(Some(Item::Scatter(class, (lobe > 0).then_some(lobe))))
    }

    /// `[atom+]` after the `[`.
    fn set(&mut self, open: usize) -> Result<Expr, Error> {
        let mut members = Vec::new();
        loop {
            self.c.skip_ws();
            match self.c.peek() {
                None => return Err(self.c.unclosed(open)),
                Some((at, ']')) => {
                    if members.is_empty() {
                        return Err(Error::new(
                            ErrorKind::Empty,
                            Span::new(at, at + 1),
                            "empty set []: expected at least one member",
                        ));
                    }
                    self.c.bump();
                    return Ok(Expr::Set(members));
                }
                Some((_, c)) if is_atom_start(c) => members.push(self.atom()?),
                Some((at, c)) => {
                    let mut err = self
                        .c
                        .unexpected(at, "a set member (an event, symbol or label) or ']'");
                    if c == '|' {
                        err = err.with_help(
                            "members of [...] are alternatives already: write [DS], not [D|S]",
                        );
                    } else if is_quantifier_start(c) {
                        err = err.with_help(
                            "quantifiers are not allowed inside [...]: quantify the whole set",
                        );
                    }
                    return Err(err);
                }
            }
        }
    }

    /// `[^item+]` after the `[^`: all items of one slot kind.
    fn negated_set(&mut self, open: usize) -> Result<Expr, Error> {
        let mut items: Vec<Item> = Vec::new();
        loop {
            self.c.skip_ws();
            match self.c.peek() {
                None => return Err(self.c.unclosed(open)),
                Some((at, ']')) => {
                    let Some(first) = items.first() else {
                        return Err(Error::new(
                            ErrorKind::Empty,
                            Span::new(at, at + 1),
                            "empty negated set [^]: expected at least one symbol or label",
                        ));
                    };
                    let kind = first.kind();
                    self.c.bump();
                    return Ok(Expr::NegSet(kind, items));
                }
                Some((at, '.' | '<' | '(' | '[')) => {
                    let span = self.c.token_span(at);
                    return Err(Error::new(
                        ErrorKind::SetMember,
                        span,
                        "a negated set [^...] holds symbols or labels only",
                    ));
                }
                Some((at, _)) => {
                    let Some(item) = self.item(at)? else {
                        return Err(self.c.unexpected(at, "a symbol, a 'label' or ']'"));
                    };
                    if let Some(first) = items.first() {
                        if first.kind() != item.kind() {
                            return Err(Error::new(
                                ErrorKind::MixedSlots,
                                Span::new(at, self.c.pos),
                                format!(
                                    "a negated set negates one slot: this {} cannot stand with {}s",
                                    kind_name(item.kind()),
                                    kind_name(first.kind())
                                ),
                            )
                            .with_help("negate each slot in an event instead, as in <[^R][^D]>"));
                        }
                    }
                    items.push(item);
                }
            }
        }
    }

    /// `<slot*>` after the `<`.
    fn event(&mut self, open: usize) -> Result<Expr, Error> {
        let mut slots = Vec::new();
        // 0: type, 1: scatter, 2 and above: labels.
        let mut index = 0usize;
        loop {
            self.c.skip_ws();
            let Some((at, c)) = self.c.peek() else {
                return Err(self.c.unclosed(open));
            };
            let slot = match c {
                '>' => {
                    self.c.bump();
                    return Ok(Expr::Event(slots));
                }
                '*' | '+' | '?' | '{' => {
                    return Err(Error::new(
                        ErrorKind::QuantifierInEvent,
                        Span::new(at, at + 1),
                        "quantifier inside <…>: quantify the whole event, as in <RD>*",
                    ))
                }
                '.' => {
                    self.c.bump();
                    Slot::Any
                }
                'x' => {
                    if index != 1 {
                        return Err(slot_kind_error(
                            Span::new(at, at + 1),
                            index,
                            "'x' (no scatter)",
                            None,
                        ));
                    }
                    self.c.bump();
                    Slot::NoScatter
                }
                '[' => {
                    let negated = self.c.peek2() == Some('^');
                    self.c.pos += if negated { 2 } else { 1 };
                    let items = self.bracket_slot_set(open, &mut index)?;
                    Slot::Set { negated, items }
                }
                '(' => {
                    self.c.bump();
                    let items = self.paren_slot_set(open, &mut index)?;
                    Slot::Set {
                        negated: false,
                        items,
                    }
                }
                _ => {
                    let Some(item) = self.item(at)? else {
                        return Err(self.c.unexpected(
                            at,
                            "an event slot (a symbol, '.', 'x', a 'label', a set) or '>'",
                        ));
                    };
                    check_slot_kind(&item, Span::new(at, self.c.pos), &mut index)?;
                    Slot::Item(item)
                }
            };
            slots.push(slot);
            index += 1;
        }
    }

    /// The members of a set inside an event slot, `[a b]` or `[^a b]`, after its opening
    /// bracket. Moves `index` to the label slots when the set holds labels.
    fn bracket_slot_set(&mut self, open: usize, index: &mut usize) -> Result<Vec<SlotItem>, Error> {
        let mut items = Vec::new();
        let mut set_kind = None;
        loop {
            self.c.skip_ws();
            match self.c.peek() {
                None => return Err(self.c.unclosed(open)),
                Some((at, ']')) => {
                    if items.is_empty() {
                        return Err(Error::new(
                            ErrorKind::Empty,
                            Span::new(at, at + 1),
                            "empty set: expected at least one member",
                        ));
                    }
                    self.c.bump();
                    return Ok(items);
                }
                Some(_) => items.push(self.slot_member(index, &mut set_kind)?),
            }
        }
    }

    /// `(a|b|…)` in an event slot, after the `(`: the guide's spelling of `[a b …]`.
    fn paren_slot_set(&mut self, open: usize, index: &mut usize) -> Result<Vec<SlotItem>, Error> {
        let mut items = Vec::new();
        let mut set_kind = None;
        self.c.skip_ws();
        match self.c.peek() {
            None => return Err(self.c.unclosed(open)),
            Some((at, ')')) => {
                return Err(Error::new(
                    ErrorKind::Empty,
                    Span::new(at, at + 1),
                    "empty set (): expected at least one member",
                ))
            }
            Some(_) => {}
        }
        loop {
            items.push(self.slot_member(index, &mut set_kind)?);
            self.c.skip_ws();
            match self.c.peek() {
                None => return Err(self.c.unclosed(open)),
                Some((_, ')')) => {
                    self.c.bump();
                    return Ok(items);
                }
                Some((_, '|')) => {
                    self.c.bump();
                    self.c.skip_ws();
                    if self.c.at_end() {
                        return Err(self.c.unclosed(open));
                    }
                }
                Some((at, _)) => return Err(self.c.unexpected(at, "'|' or ')'")),
            }
        }
    }

    /// One member of a set in an event slot; all members must be of one slot kind.
    fn slot_member(
        &mut self,
        index: &mut usize,
        set_kind: &mut Option<SlotKind>,
    ) -> Result<SlotItem, Error> {
        let Some((at, c)) = self.c.peek() else {
            return Err(Error::new(
                ErrorKind::Unclosed,
                Span::at(self.c.src.len()),
                "expected a set member",
            ));
        };
        if matches!(c, '.' | '<' | '(' | '[' | '|' | ')') {
            return Err(set_member_error(self.c.token_span(at)));
        }
        if c == 'x' {
            let slot = if *set_kind == Some(SlotKind::Label) {
                2
            } else {
                *index
            };
            if slot != 1 {
                return Err(slot_kind_error(
                    Span::new(at, at + 1),
                    slot,
                    "'x' (no scatter)",
                    None,
                ));
            }
            self.c.bump();
            set_kind.get_or_insert(SlotKind::Scatter);
            return Ok(SlotItem::NoScatter);
        }
        let Some(item) = self.item(at)? else {
            return Err(self.c.unexpected(at, "a symbol or a 'label'"));
        };
        let span = Span::new(at, self.c.pos);
        match *set_kind {
            None => {
                check_slot_kind(&item, span, index)?;
                *set_kind = Some(item.kind());
            }
            Some(kind) if kind != item.kind() => {
                let slot = match kind {
                    SlotKind::Type => 0,
                    SlotKind::Scatter => 1,
                    SlotKind::Label => 2,
                };
                return Err(slot_kind_error(
                    span,
                    slot,
                    &describe_item(&item),
                    Some(&item),
                ));
            }
            Some(_) => {}
        }
        Ok(SlotItem::Item(item))
    }
}

fn set_member_error(span: Span) -> Error {
    Error::new(
        ErrorKind::SetMember,
        span,
        "expected a set member: a symbol or a 'label'",
    )
}

fn kind_name(kind: SlotKind) -> &'static str {
    match kind {
        SlotKind::Type => "event type",
        SlotKind::Scatter => "scatter symbol",
        SlotKind::Label => "label",
    }
}

fn describe_item(item: &Item) -> String {
    match item {
        Item::Type(t) => format!("event type '{}'", t.letter()),
        Item::Scatter(c, Some(n)) => format!("scatter '{}{n}'", c.letter()),
        Item::Scatter(c, None) => format!("scatter '{}'", c.letter()),
        Item::Label(l) => format!("label '{l}'"),
    }
}

/// Checks that `item` fits the slot at `index`; a label moves `index` to the label slots.
fn check_slot_kind(item: &Item, span: Span, index: &mut usize) -> Result<(), Error> {
    let fits = match (item.kind(), *index) {
        (SlotKind::Label, i) => {
            *index = i.max(2);
            true
        }
        (SlotKind::Type, 0) | (SlotKind::Scatter, 1) => true,
        _ => false,
    };
    if fits {
        Ok(())
    } else {
        Err(slot_kind_error(
            span,
            *index,
            &describe_item(item),
            Some(item),
        ))
    }
}

fn slot_kind_error(span: Span, index: usize, what: &str, item: Option<&Item>) -> Error {
    let (slot, expected) = match index {
        0 => (
            "type slot",
            "an event type C R T L O V B, '.', a set of them, or a 'label'",
        ),
        1 => (
            "scatter slot",
            "a scatter D S U (numbered or not), 'x', '.', a set of them, or a 'label'",
        ),
        _ => ("label slot", "a 'label', a set of labels, or '.'"),
    };
    let err = Error::new(
        ErrorKind::SlotKind,
        span,
        format!("{what} cannot stand in the {slot}: expected {expected}"),
    );
    match (index, item) {
        (0, Some(Item::Scatter(c, n))) => {
            let sym = format!("{}{}", c.letter(), n.map(|n| n.to_string()).unwrap_or_default());
            err.with_help(format!("did you mean `<.{sym}>`? (the first slot is the event type)"))
        }
        (1, Some(Item::Type(t))) => err.with_help(format!(
            "'{}' is an event type: it belongs in the first slot, or as its own event after '>'",
            t.letter()
        )),
        (_, Some(Item::Type(_) | Item::Scatter(..))) if index >= 2 => {
            err.with_help("after the first label every slot is a label: type and scatter come first, as in <RD'name'>")
        }
        _ => err,
    }
}

fn prefix_list() -> String {
    Prefix::ALL.map(Prefix::word).join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn error(src: &str) -> Error {
        parse_definition(src).unwrap_err()
    }

    #[test]
    fn nesting_beyond_the_limit_is_an_error_at_the_bracket_that_goes_too_deep() {
        let ok = format!(
            "C{}L{}",
            "(".repeat(MAX_NESTING as usize),
            ")".repeat(MAX_NESTING as usize)
        );
        assert!(parse_definition(&ok).is_ok());
        for open in ["(", "["] {
            let close = if open == "(" { ")" } else { "]" };
            let deep = format!("C{}L{}", open.repeat(9000), close.repeat(9000));
            let e = error(&deep);
            assert_eq!(e.kind, ErrorKind::Nesting);
            let at = 1 + MAX_NESTING as usize;
            assert_eq!(e.span, Span::new(at, at + 1));
        }
    }

    #[test]
    fn a_long_chain_of_alternatives_is_flat() {
        let chain = format!("C({}D)L", "D|".repeat(100_000));
        let def = parse_definition(&chain).unwrap();
        let Body::Expr(Expr::Concat(units)) = def.body else {
            panic!("not a sequence");
        };
        let Expr::Group(inner) = &units[1] else {
            panic!("not a group");
        };
        assert!(matches!(&**inner, Expr::Alt(arms) if arms.len() == 100_001));
    }

    #[test]
    fn a_zero_for_an_o_gets_a_hint_and_a_numbered_symbol_in_a_quantifier_is_whole() {
        let e = error("C<RD>[<L.>0]");
        assert_eq!(e.span, Span::new(10, 11));
        assert!(
            e.help
                .as_deref()
                .is_some_and(|h| h.contains("did you mean 'O'")),
            "{e:?}"
        );
        let e = error("C<RD>{,D4}");
        assert_eq!(
            (e.kind, e.span),
            (ErrorKind::QuantifierSyntax, Span::new(7, 9))
        );
        let e = error("CD{a}L");
        assert_eq!(e.span, Span::new(3, 4));
    }
}
