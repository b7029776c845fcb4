//! Lowering: the syntax tree becomes a regular expression over *event predicates*, each a
//! conjunction of a type set, a scatter set and label-set constraints (docs/lpe.md#atoms–4).

use crate::event::{
    class_mask, scatter_bit, Event, EventType, Scatter, ScatterClass, ALL_SCATTERS,
};
use crate::syntax::ast::{Expr, Item, Slot, SlotItem, SlotKind};

const ALL_TYPES: u8 = (1 << 7) - 1;

/// Every scatter but the user (data) lobes: what `.` and bare types mean.
fn lighting_scatters() -> u64 {
    ALL_SCATTERS & !class_mask(ScatterClass::User)
}

/// A constraint on an event's label set.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum LabelCond {
    /// Contains at least one of these labels.
    AnyOf(Vec<String>),
    /// Contains none of these labels.
    NoneOf(Vec<String>),
}

impl LabelCond {
    fn matches(&self, e: &Event) -> bool {
        match self {
            LabelCond::AnyOf(ls) => ls.iter().any(|l| e.has_label(l)),
            LabelCond::NoneOf(ls) => !ls.iter().any(|l| e.has_label(l)),
        }
    }
}

/// A predicate over one event.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Pred {
    /// One bit per [`EventType`].
    pub types: u8,
    /// One bit per concrete scatter (see `event::scatter_bit`).
    pub scatters: u64,
    /// All must hold; sorted, so equal predicates compare equal.
    pub labels: Vec<LabelCond>,
}

impl Pred {
    fn new(types: u8, scatters: u64, mut labels: Vec<LabelCond>) -> Pred {
        labels.sort();
        labels.dedup();
        Pred {
            types,
            scatters,
            labels,
        }
    }

    pub fn matches(&self, e: &Event) -> bool {
        self.types & e.ty.bit() != 0
            && self.scatters & (1u64 << scatter_bit(e.scatter)) != 0
            && self.labels.iter().all(|c| c.matches(e))
    }

    /// True if no event at all can satisfy it.
    pub fn is_empty(&self) -> bool {
        self.types == 0 || self.scatters == 0
    }

    /// The same predicate with the given types removed.
    pub fn without_types(&self, types: u8) -> Pred {
        Pred {
            types: self.types & !types,
            ..self.clone()
        }
    }

    /// Labels the predicate mentions, for the default alphabet.
    pub fn mentioned_labels(&self) -> impl Iterator<Item = &str> {
        self.labels.iter().flat_map(|c| match c {
            LabelCond::AnyOf(ls) | LabelCond::NoneOf(ls) => ls.iter().map(String::as_str),
        })
    }
}

/// A regular expression over event predicates.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Hir {
    Event(Pred),
    Concat(Vec<Hir>),
    Alt(Vec<Hir>),
    Repeat {
        hir: Box<Hir>,
        min: u32,
        max: Option<u32>,
    },
}

impl Hir {
    /// Calls `f` on every predicate.
    pub fn visit_preds<'a>(&'a self, f: &mut impl FnMut(&'a Pred)) {
        match self {
            Hir::Event(p) => f(p),
            Hir::Concat(v) | Hir::Alt(v) => v.iter().for_each(|h| h.visit_preds(f)),
            Hir::Repeat { hir, .. } => hir.visit_preds(f),
        }
    }

    /// The same expression with every predicate mapped.
    pub fn map_preds(&self, f: &impl Fn(&Pred) -> Pred) -> Hir {
        match self {
            Hir::Event(p) => Hir::Event(f(p)),
            Hir::Concat(v) => Hir::Concat(v.iter().map(|h| h.map_preds(f)).collect()),
            Hir::Alt(v) => Hir::Alt(v.iter().map(|h| h.map_preds(f)).collect()),
            Hir::Repeat { hir, min, max } => Hir::Repeat {
                hir: Box::new(hir.map_preds(f)),
                min: *min,
                max: *max,
            },
        }
    }
}

pub fn lower(e: &Expr) -> Hir {
    match e {
        Expr::Concat(v) => Hir::Concat(v.iter().map(lower).collect()),
        Expr::Alt(arms) => Hir::Alt(arms.iter().map(lower).collect()),
        Expr::Repeat { expr, min, max } => Hir::Repeat {
            hir: Box::new(lower(expr)),
            min: *min,
            max: *max,
        },
        Expr::Group(inner) => lower(inner),
        Expr::Set(members) => Hir::Alt(members.iter().map(lower).collect()),
        Expr::NegSet(kind, items) => Hir::Event(match kind {
            SlotKind::Type => Pred::new(
                ALL_TYPES & !type_bits(items.iter()),
                lighting_scatters(),
                vec![],
            ),
            // A negated scatter slot admits user lobes (docs/lpe.md#events-in-angle-brackets).
            SlotKind::Scatter => Pred::new(
                ALL_TYPES,
                ALL_SCATTERS & !scatter_bits(items.iter()),
                vec![],
            ),
            SlotKind::Label => Pred::new(
                ALL_TYPES,
                lighting_scatters(),
                vec![LabelCond::NoneOf(label_list(items.iter()))],
            ),
        }),
        Expr::Any => Hir::Event(Pred::new(ALL_TYPES, lighting_scatters(), vec![])),
        Expr::Item(item) => Hir::Event(match item {
            Item::Type(t) => Pred::new(t.bit(), lighting_scatters(), vec![]),
            Item::Scatter(..) => Pred::new(ALL_TYPES, scatter_bits(std::iter::once(item)), vec![]),
            Item::Label(l) => Pred::new(
                ALL_TYPES,
                lighting_scatters(),
                vec![LabelCond::AnyOf(vec![l.clone()])],
            ),
        }),
        Expr::Event(slots) => Hir::Event(lower_event(slots)),
    }
}

fn lower_event(slots: &[Slot]) -> Pred {
    let mut types = ALL_TYPES;
    let mut scatters = lighting_scatters();
    let mut labels = Vec::new();
    // The parser has checked slot kinds; a slot's meaning follows from what it holds.
    let mut index = 0usize;
    for slot in slots {
        let kind = slot_kind(slot, index);
        match kind {
            SlotKind::Label => {
                index = index.max(2);
                match slot {
                    Slot::Any => {}
                    Slot::Item(Item::Label(l)) => labels.push(LabelCond::AnyOf(vec![l.clone()])),
                    Slot::Set { negated, items } => {
                        let ls = label_list(items.iter().filter_map(slot_item));
                        labels.push(if *negated {
                            LabelCond::NoneOf(ls)
                        } else {
                            LabelCond::AnyOf(ls)
                        });
                    }
                    _ => {}
                }
            }
            SlotKind::Type => {
                types = match slot {
                    Slot::Any => ALL_TYPES,
                    Slot::Item(i) => type_bits(std::iter::once(i)),
                    Slot::Set { negated, items } => {
                        let bits = type_bits(items.iter().filter_map(slot_item));
                        if *negated {
                            ALL_TYPES & !bits
                        } else {
                            bits
                        }
                    }
                    Slot::NoScatter => ALL_TYPES,
                }
            }
            SlotKind::Scatter => {
                scatters = match slot {
                    Slot::Any => lighting_scatters(),
                    Slot::NoScatter => 1 << scatter_bit(None),
                    Slot::Item(i) => scatter_bits(std::iter::once(i)),
                    Slot::Set { negated, items } => {
                        let mut bits = scatter_bits(items.iter().filter_map(slot_item));
                        if items.contains(&SlotItem::NoScatter) {
                            bits |= 1 << scatter_bit(None);
                        }
                        if *negated {
                            ALL_SCATTERS & !bits
                        } else {
                            bits
                        }
                    }
                }
            }
        }
        index += 1;
    }
    Pred::new(types, scatters, labels)
}

/// The kind of the slot at `index`, given what it holds (labels jump to the label slots).
fn slot_kind(slot: &Slot, index: usize) -> SlotKind {
    let holds_labels = match slot {
        Slot::Item(i) => i.kind() == SlotKind::Label,
        Slot::Set { items, .. } => items
            .iter()
            .any(|i| matches!(i, SlotItem::Item(Item::Label(_)))),
        _ => false,
    };
    match index {
        _ if holds_labels => SlotKind::Label,
        0 => SlotKind::Type,
        1 => SlotKind::Scatter,
        _ => SlotKind::Label,
    }
}

fn slot_item(i: &SlotItem) -> Option<&Item> {
    match i {
        SlotItem::Item(i) => Some(i),
        SlotItem::NoScatter => None,
    }
}

fn type_bits<'a>(items: impl Iterator<Item = &'a Item>) -> u8 {
    items.fold(0, |acc, i| match i {
        Item::Type(t) => acc | t.bit(),
        _ => acc,
    })
}

fn scatter_bits<'a>(items: impl Iterator<Item = &'a Item>) -> u64 {
    items.fold(0, |acc, i| match i {
        Item::Scatter(class, None) => acc | class_mask(*class),
        Item::Scatter(class, Some(n)) => acc | 1u64 << scatter_bit(Some(Scatter::new(*class, *n))),
        _ => acc,
    })
}

fn label_list<'a>(items: impl Iterator<Item = &'a Item>) -> Vec<String> {
    let mut v: Vec<String> = items
        .filter_map(|i| match i {
            Item::Label(l) => Some(l.clone()),
            _ => None,
        })
        .collect();
    v.sort();
    v.dedup();
    v
}

/// The event types the generic profile does not emit (docs/lpe.md#paths-and-events): B.
pub const RESERVED_TYPES: u8 = 1 << EventType::Background as u8;
