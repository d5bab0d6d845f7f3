//! Scenario files and label tables changed at random (numbers replaced by hostile values,
//! characters changed) give an error naming the file or a valid configuration, never a
//! panic.

#![allow(clippy::unwrap_used)] // tests fail loudly by design

use std::path::{Path, PathBuf};
use std::sync::LazyLock;

use myoslice::prelude::*;
use myoslice::scenario::Scenario;
use proptest::prelude::*;

fn asset(rel: &str) -> String {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../assets")
        .join(rel);
    std::fs::read_to_string(&p).unwrap()
}

/// The phantom's label table as JSON (made once: the phantom's volume takes a while).
static PHANTOM_TABLE: LazyLock<String> =
    LazyLock::new(|| Phantom::default().generate().unwrap().1.to_json());

/// Values a hostile or careless file might hold where a number belongs.
const HOSTILE: [&str; 12] = [
    "nan",
    "inf",
    "-inf",
    "-1",
    "0",
    "1e300",
    "-1e300",
    "1e-300",
    "4294967296",
    "18446744073709551616",
    "\"x\"",
    "[]",
];

/// `text` with the `which`-th numbers (by start position, cycling) replaced by hostile
/// values, and `edits` characters replaced.
fn mutate(text: &str, numbers: &[(usize, usize)], edits: &[(usize, char)]) -> String {
    let starts: Vec<usize> = text
        .char_indices()
        .filter(|&(i, c)| {
            c.is_ascii_digit()
                && text[..i]
                    .chars()
                    .next_back()
                    .is_none_or(|p| !p.is_ascii_alphanumeric() && p != '.' && p != '_')
        })
        .map(|(i, _)| i)
        .collect();
    let mut out = text.to_string();
    if !starts.is_empty() {
        let mut chosen: Vec<(usize, &str)> = numbers
            .iter()
            .map(|&(n, v)| (starts[n % starts.len()], HOSTILE[v % HOSTILE.len()]))
            .collect();
        chosen.sort_unstable();
        chosen.dedup_by_key(|c| c.0);
        for &(at, value) in chosen.iter().rev() {
            let end = out[at..]
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '.' || c == '-' || c == '+'))
                .map_or(out.len(), |e| at + e);
            out.replace_range(at..end, value);
        }
    }
    let mut chars: Vec<char> = out.chars().collect();
    for &(at, c) in edits {
        if !chars.is_empty() {
            let n = chars.len();
            chars[at % n] = c;
        }
    }
    chars.into_iter().collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn a_changed_scenario_is_refused_or_valid(
        file in 0usize..4,
        numbers in proptest::collection::vec((0usize..64, 0usize..12), 0..4),
        edits in proptest::collection::vec((0usize..4000, any::<char>()), 0..3),
    ) {
        let name = ["knee_flexion", "knee_extension", "co_contraction", "fast_flexion"][file];
        let text = mutate(&asset(&format!("scenarios/{name}.toml")), &numbers, &edits);
        let path = Path::new("hostile.toml");
        match Scenario::from_str_at(&text, path) {
            Err(e) => prop_assert!(e.to_string().contains("hostile.toml"), "{e}"),
            Ok(s) => {
                // What parses is checked before anything is built from it.
                let _ = s.config().validate();
                let _ = s.build_options().validate();
            }
        }
    }

    #[test]
    fn a_changed_label_table_is_refused_or_valid(
        numbers in proptest::collection::vec((0usize..200, 0usize..12), 0..4),
        edits in proptest::collection::vec((0usize..20000, any::<char>()), 0..3),
    ) {
        let text = mutate(&PHANTOM_TABLE, &numbers, &edits);
        if let Err(e) = LabelTable::from_json_str(&text, "hostile.json") {
            prop_assert!(e.to_string().contains("hostile.json"), "{e}");
        }
    }

    /// A segmentation tool's label list (ITK-SNAP, Slicer) with numbers and characters
    /// changed: refused naming the file, or read and mapped (unknown names as fat).
    #[test]
    fn a_changed_label_list_is_refused_or_mapped(
        slicer in any::<bool>(),
        numbers in proptest::collection::vec((0usize..300, 0usize..12), 0..4),
        edits in proptest::collection::vec((0usize..4000, any::<char>()), 0..3),
    ) {
        let text = mutate(if slicer { &SLICER_LIST } else { &ITK_SNAP_LIST }, &numbers, &edits);
        let names = myoslice::label_names::AnatomyNames::builtin().unwrap();
        let read = myoslice::io::parse_label_list(&text, "hostile.txt").and_then(|list| {
            myoslice::label_names::map_labels(&list, names, Unmapped::Fat, "hostile.txt")
        });
        if let Err(e) = read {
            prop_assert!(e.to_string().contains("hostile.txt"), "{e}");
        }
    }
}

/// The phantom's labels as ITK-SNAP and Slicer write them.
static ITK_SNAP_LIST: LazyLock<String> = LazyLock::new(|| {
    let mut s = String::from("# ITK-SnAP Label Description File\n");
    for l in phantom_labels() {
        s += &format!(
            "{} 12 200 30 0.5 1 1 \"{}\"\n",
            l.id,
            l.name.replace('_', " ")
        );
    }
    s
});
static SLICER_LIST: LazyLock<String> = LazyLock::new(|| {
    let mut s = String::from("# Color table file seg.ctbl\n");
    for l in phantom_labels() {
        s += &format!("{} {} 12 200 30 255\n", l.id, l.name);
    }
    s
});

fn phantom_labels() -> Vec<myoslice::Label> {
    let (_, table) = Phantom::default().generate().unwrap();
    table.labels().to_vec()
}

#[test]
fn the_mutation_replaces_whole_numbers_and_characters() {
    let text = "rate_hz = 1.5e2\nvalues = [2, -3]\nname = \"m2\"\n";
    assert_eq!(
        mutate(text, &[(0, 0), (1, 3)], &[]),
        "rate_hz = nan\nvalues = [-1, -3]\nname = \"m2\"\n"
    );
    assert_eq!(mutate("ab", &[], &[(1, 'x')]), "ax");
}
