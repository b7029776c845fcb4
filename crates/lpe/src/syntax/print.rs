//! Syntax tree back to text. `parse(print(ast))` gives `ast` again (with `G` printed as
//! its canonical `S`).

use super::ast::{Body, Definition, Expr, Item, Slot, SlotItem};
use std::fmt::Write;

pub fn print_definition(def: &Definition) -> String {
    let mut out = String::new();
    if let Some(name) = &def.name {
        let _ = write!(out, "{name}=");
    }
    if def.lpe_marker {
        out.push_str("lpe:");
    }
    for p in &def.prefixes {
        let _ = write!(out, "{};", p.word());
    }
    match &def.body {
        Body::Expr(e) => print_expr(e, &mut out),
        Body::Standard(name) => out.push_str(name),
    }
    out
}

pub(crate) fn print_expr(e: &Expr, out: &mut String) {
    match e {
        Expr::Concat(units) => units.iter().for_each(|u| print_expr(u, out)),
        Expr::Alt(arms) => {
            for (i, arm) in arms.iter().enumerate() {
                if i > 0 {
                    out.push('|');
                }
                print_expr(arm, out);
            }
        }
        Expr::Repeat { expr, min, max } => {
            print_expr(expr, out);
            match (min, max) {
                (0, None) => out.push('*'),
                (1, None) => out.push('+'),
                (0, Some(1)) => out.push('?'),
                (n, None) => {
                    let _ = write!(out, "{{{n},}}");
                }
                (n, Some(m)) if n == m => {
                    let _ = write!(out, "{{{n}}}");
                }
                (n, Some(m)) => {
                    let _ = write!(out, "{{{n},{m}}}");
                }
            }
        }
        Expr::Group(inner) => {
            out.push('(');
            print_expr(inner, out);
            out.push(')');
        }
        Expr::Set(members) => {
            out.push('[');
            members.iter().for_each(|m| print_expr(m, out));
            out.push(']');
        }
        Expr::NegSet(_, items) => {
            out.push_str("[^");
            items.iter().for_each(|i| print_item(i, out));
            out.push(']');
        }
        Expr::Any => out.push('.'),
        Expr::Item(i) => print_item(i, out),
        Expr::Event(slots) => {
            out.push('<');
            for s in slots {
                match s {
                    Slot::Any => out.push('.'),
                    Slot::NoScatter => out.push('x'),
                    Slot::Item(i) => print_item(i, out),
                    Slot::Set { negated, items } => {
                        out.push_str(if *negated { "[^" } else { "[" });
                        for (k, i) in items.iter().enumerate() {
                            if k > 0 {
                                out.push(' ');
                            }
                            match i {
                                SlotItem::Item(i) => print_item(i, out),
                                SlotItem::NoScatter => out.push('x'),
                            }
                        }
                        out.push(']');
                    }
                }
            }
            out.push('>');
        }
    }
}

fn print_item(i: &Item, out: &mut String) {
    match i {
        Item::Type(t) => out.push(t.letter()),
        Item::Scatter(c, lobe) => {
            out.push(c.letter());
            if let Some(n) = lobe {
                let _ = write!(out, "{n}");
                // A following digit would be read as part of the number: nothing can
                // follow here but symbols, labels and brackets, so no separator needed.
            }
        }
        Item::Label(l) => {
            let _ = write!(out, "'{l}'");
        }
    }
}
