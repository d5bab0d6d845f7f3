//! Label files as segmentation tools write them, with the names people give structures.

use std::fmt::Write as _;

use myoslice::{LabelTable, TissueKind};

/// How a person might name a structure in a segmentation tool.
pub fn human(name: &str, k: usize) -> String {
    let words = name.replace('_', " ");
    match k % 4 {
        0 => format!("Left {words}"),
        1 => format!("M. {}", capitalised(&words)),
        2 => format!("{} (L)", words.to_uppercase()),
        _ => format!("{}_l", words.replace(' ', "")),
    }
}

fn capitalised(s: &str) -> String {
    let mut c = s.chars();
    c.next()
        .map(|f| f.to_uppercase().chain(c).collect())
        .unwrap_or_default()
}

/// `table` as an ITK-SNAP label description file.
pub fn itk_snap(table: &LabelTable) -> String {
    let mut s = String::from(
        "################################################\n\
         # ITK-SnAP Label Description File\n\
         # IDX   -R-  -G-  -B-  -A--  VIS MSH  LABEL\n\
         ################################################\n",
    );
    for (k, l) in table.labels().iter().enumerate() {
        let name = if l.kind == TissueKind::Background {
            "Clear Label".to_string()
        } else {
            human(&l.name, k)
        };
        writeln!(
            s,
            "{:>5} {:>5} {:>4} {:>4} {:>8} 1 1 \"{name}\"",
            l.id,
            k * 5,
            40,
            200,
            1
        )
        .unwrap();
    }
    s
}

/// `table` as a 3D Slicer colour table.
pub fn slicer(table: &LabelTable) -> String {
    let mut s = String::from("# Color table file seg.ctbl\n");
    for (k, l) in table.labels().iter().enumerate() {
        let name = human(&l.name, k + 1).replace(' ', "_");
        writeln!(s, "{} {name} {} 40 200 255", l.id, k * 5).unwrap();
    }
    s
}
