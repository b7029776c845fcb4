//! "Did you mean …?" for names a user types: built-in scenes, AOVs, light groups and LPE
//! labels. The closest candidate by edit distance, if it is close enough to be a typo.

/// ` (did you mean 'x'?)` for the candidate closest to `word`, or nothing when none is
/// within a typo's distance: a third of the word's length, at least one edit. Case
/// differences count as half an edit, so `Key` finds `key` before `kex` does.
pub fn did_you_mean<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> String {
    if word.is_empty() {
        return String::new();
    }
    let limit = (word.chars().count() / 3).max(1) * 2;
    candidates
        .into_iter()
        .filter(|c| *c != word)
        .map(|c| (distance(word, c), c))
        .filter(|(d, _)| *d <= limit)
        .min()
        .map_or_else(String::new, |(_, c)| format!(" (did you mean '{c}'?)"))
}

/// Levenshtein distance in half edits: 1 for a change of case only, 2 for any other edit.
fn distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).map(|j| 2 * j).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = 2 * (i + 1);
        for (j, cb) in b.iter().enumerate() {
            let change = if ca == *cb {
                0
            } else if ca.eq_ignore_ascii_case(cb) {
                1
            } else {
                2
            };
            let next = (diagonal + change).min(row[j] + 2).min(row[j + 1] + 2);
            diagonal = row[j + 1];
            row[j + 1] = next;
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn typos_find_their_word_and_strangers_find_nothing() {
        let scenes = ["cornell", "cornell-classic", "materials", "many-lights"];
        assert_eq!(did_you_mean("cornel", scenes), " (did you mean 'cornell'?)");
        assert_eq!(
            did_you_mean("many-light", scenes),
            " (did you mean 'many-lights'?)"
        );
        assert_eq!(did_you_mean("kitchen", scenes), "");
        assert_eq!(
            did_you_mean("directdiffuse", ["directDiffuse", "directSpecular"]),
            " (did you mean 'directDiffuse'?)"
        );
        assert_eq!(
            did_you_mean("Key", ["kex", "key"]),
            " (did you mean 'key'?)"
        );
        assert_eq!(did_you_mean("", ["a"]), "");
    }

    #[test]
    fn distance_counts_edits() {
        assert_eq!(distance("kitten", "sitting"), 6);
        assert_eq!(distance("", "abc"), 6);
        assert_eq!(distance("abc", "abc"), 0);
        assert_eq!(distance("abc", "ABC"), 3);
    }
}
