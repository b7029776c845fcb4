//! The syntax tree of one AOV definition, as written (before lowering).

use crate::event::{EventType, ScatterClass};
use crate::prefix::Prefix;

/// `[NAME =] [lpe:] {PREFIX ;} (expression | standard name)`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Definition {
    pub name: Option<String>,
    pub lpe_marker: bool,
    pub prefixes: Vec<Prefix>,
    pub body: Body,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Body {
    Expr(Expr),
    /// A standard name after `lpe:` (docs/lpe.md#standard-aovs), in its canonical spelling.
    Standard(&'static str),
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Expr {
    /// Events one after another.
    Concat(Vec<Expr>),
    /// `a|b|…`: one of the units joined by bars (a flat list, so a long chain of
    /// alternatives does not nest: every pass over the tree recurses only as deep as the
    /// groups and sets are nested, which the parser bounds).
    Alt(Vec<Expr>),
    Repeat {
        expr: Box<Expr>,
        min: u32,
        max: Option<u32>,
    },
    Group(Box<Expr>),
    /// `[a b …]`: any of the member atoms.
    Set(Vec<Expr>),
    /// `[^…]`: every member in one slot, that slot negated, the others free.
    NegSet(SlotKind, Vec<Item>),
    /// `.`
    Any,
    /// A bare symbol or label: one whole event.
    Item(Item),
    /// `<slot slot …>`
    Event(Vec<Slot>),
}

/// Which part of an event an item constrains.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SlotKind {
    Type,
    Scatter,
    Label,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Item {
    Type(EventType),
    /// A scatter class, `lobe == None` for any number.
    Scatter(ScatterClass, Option<u8>),
    Label(String),
}

impl Item {
    pub fn kind(&self) -> SlotKind {
        match self {
            Item::Type(_) => SlotKind::Type,
            Item::Scatter(..) => SlotKind::Scatter,
            Item::Label(_) => SlotKind::Label,
        }
    }
}

/// One member of a set written inside an event slot: an item, or `x` (no scatter).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SlotItem {
    Item(Item),
    NoScatter,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Slot {
    /// `.`: no constraint.
    Any,
    /// `x`: no scatter.
    NoScatter,
    Item(Item),
    /// `[a b]`, `(a|b)` or, negated, `[^a b]`.
    Set {
        negated: bool,
        items: Vec<SlotItem>,
    },
}
