//! Rules in plain English, for `lightpath lpe explain`.

use crate::event::ScatterClass;
use crate::runtime::Rule;
use crate::syntax::ast::{Body, Expr, Item, Slot, SlotItem, SlotKind};

/// One sentence describing what paths the rule collects.
pub fn explain(rule: &Rule) -> String {
    let def = rule.definition();
    let mut out = String::new();
    if let Body::Standard(name) = &def.body {
        out.push_str(&format!("the standard '{name}' ({}): ", rule.expression));
    }
    let parsed = crate::syntax::parse_definition(&rule.expression);
    match parsed.map(|d| d.body) {
        Ok(Body::Expr(e)) => out.push_str(&describe(&e)),
        _ => out.push_str(&rule.expression),
    }
    let flags: Vec<String> = rule
        .flags
        .iter()
        .map(|p| format!("{} ({})", p.word(), p.describe()))
        .collect();
    if !flags.is_empty() {
        out.push_str("; ");
        out.push_str(&flags.join("; "));
    }
    out
}

fn describe(e: &Expr) -> String {
    match e {
        Expr::Concat(units) => units
            .iter()
            .map(describe)
            .collect::<Vec<_>>()
            .join(", then "),
        Expr::Alt(arms) => format!(
            "either {}",
            arms.iter().map(describe).collect::<Vec<_>>().join(" or ")
        ),
        Expr::Repeat { expr, min, max } => {
            let inner = describe(expr);
            match (min, max) {
                (0, None) => format!("any number of ({inner})"),
                (1, None) => format!("one or more of ({inner})"),
                (0, Some(1)) => format!("optionally ({inner})"),
                (n, None) => format!("{n} or more of ({inner})"),
                (n, Some(m)) if n == m => format!("exactly {n} of ({inner})"),
                (n, Some(m)) => format!("{n} to {m} of ({inner})"),
            }
        }
        Expr::Group(inner) => describe(inner),
        Expr::Set(members) => {
            let parts: Vec<String> = members.iter().map(describe).collect();
            if parts.len() == 1 {
                parts[0].clone()
            } else {
                format!("one of: {}", parts.join(" / "))
            }
        }
        Expr::NegSet(kind, items) => {
            let names: Vec<String> = items.iter().map(item_name).collect();
            match kind {
                SlotKind::Label => format!("any event on none of {}", names.join(", ")),
                _ => format!("any event except {}", names.join(", ")),
            }
        }
        Expr::Any => "any event (not a data lobe)".into(),
        Expr::Item(Item::Label(l)) => format!("any event on '{l}'"),
        Expr::Item(i) => item_name(i),
        Expr::Event(slots) => describe_event(slots),
    }
}

fn item_name(i: &Item) -> String {
    match i {
        Item::Type(t) => t.describe().to_string(),
        Item::Scatter(c, n) => {
            let class = match c {
                ScatterClass::Diffuse => "diffuse",
                ScatterClass::Specular => "specular",
                ScatterClass::User => "user-data",
            };
            match n {
                Some(n) => format!("a {class} scatter through lobe {}{n}", c.letter()),
                None => format!("a {class} scatter"),
            }
        }
        Item::Label(l) => format!("'{l}'"),
    }
}

fn slot_items(items: &[SlotItem]) -> String {
    items
        .iter()
        .map(|i| match i {
            SlotItem::Item(i) => item_name(i),
            SlotItem::NoScatter => "no scatter".into(),
        })
        .collect::<Vec<_>>()
        .join(" or ")
}

fn describe_event(slots: &[Slot]) -> String {
    let mut parts = Vec::new();
    for (i, s) in slots.iter().enumerate() {
        let text = match s {
            Slot::Any => continue,
            Slot::NoScatter => "with no scatter".to_string(),
            Slot::Item(Item::Label(l)) => format!("on '{l}'"),
            Slot::Item(item) if i == 1 => format!("through {}", item_name(item)),
            Slot::Item(item) => item_name(item),
            Slot::Set {
                negated: false,
                items,
            } => format!("being {}", slot_items(items)),
            Slot::Set {
                negated: true,
                items,
            } => format!("not {}", slot_items(items)),
        };
        parts.push(text);
    }
    if parts.is_empty() {
        "any event (not a data lobe)".into()
    } else {
        format!("an event: {}", parts.join(", "))
    }
}
