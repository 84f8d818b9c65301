//! The codes of a panel: each code its lanes raised, its colour (the hue
//! of its class, a lightness of its own among the class's codes) and its
//! description through the node's profile. Bars take their colour from
//! here and the legend lists it, so both always agree.

use std::collections::{BTreeMap, BTreeSet};

use super::lane::Lane;
use super::style::{SHADES, class_index, code_colour, dark};
use crate::canopen::codes;

/// Descriptions kept per code: nodes with different profiles can describe
/// one code differently; more than two is noise in a legend.
const TEXTS_PER_CODE: usize = 2;

#[derive(Debug)]
pub(super) struct CodeKey {
    /// Index of the code's class ([`class_index`]).
    pub(super) class: usize,
    /// Its lightness step within the class (0: the class colour).
    pub(super) shade: usize,
    pub(super) texts: Vec<String>,
}

impl CodeKey {
    /// The CSS classes of a bar or swatch of this code.
    pub(super) fn css(&self, class_slug: &str) -> String {
        match self.shade % SHADES {
            0 => format!("c-{class_slug}"),
            k => format!("c-{class_slug} k{k}"),
        }
    }

    /// A label on this code's fill is white.
    pub(super) fn dark(&self) -> bool {
        dark(code_colour(self.class, self.shade))
    }
}

/// Every code of a panel, ascending.
#[derive(Debug, Default)]
pub(super) struct CodeKeys {
    pub(super) codes: BTreeMap<u16, CodeKey>,
}

impl CodeKeys {
    pub(super) fn of(lanes: &[Lane<'_>]) -> CodeKeys {
        let mut codes: BTreeMap<u16, CodeKey> = BTreeMap::new();
        let mut add = |code: u16, text: &str| {
            let key = codes.entry(code).or_insert_with(|| CodeKey {
                class: class_index(codes::lookup(code).class),
                shade: 0,
                texts: Vec::new(),
            });
            if key.texts.len() < TEXTS_PER_CODE && !key.texts.iter().any(|t| t == text) {
                key.texts.push(text.to_string());
            }
        };
        for lane in lanes {
            for (code, text) in lane.node.descriptions.iter() {
                add(code, text);
            }
            // Every drawn code is one the node raised; kept for safety.
            for bar in &lane.bars.bars {
                let code = bar.code();
                if lane.node.descriptions.get(code).is_none() {
                    add(code, &lane.node.describe(code));
                }
            }
        }
        // Shades in code order within each class.
        let mut next = BTreeMap::<usize, usize>::new();
        for key in codes.values_mut() {
            let n = next.entry(key.class).or_default();
            key.shade = *n;
            *n += 1;
        }
        CodeKeys { codes }
    }

    /// The `(class, shade)` pairs the style sheet needs rules for.
    pub(super) fn shades(&self) -> BTreeSet<(usize, usize)> {
        self.codes
            .values()
            .map(|k| (k.class, k.shade % SHADES))
            .filter(|&(_, s)| s > 0)
            .collect()
    }

    /// Codes in legend order: by class, then by code.
    pub(super) fn in_legend_order(&self) -> Vec<(u16, &CodeKey)> {
        let mut v: Vec<(u16, &CodeKey)> = self.codes.iter().map(|(c, k)| (*c, k)).collect();
        v.sort_by_key(|(c, k)| (k.class, *c));
        v
    }
}
