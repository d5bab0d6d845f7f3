//! Label lists of segmentation tools: an ITK-SNAP label description file and a 3D Slicer
//! colour table give each label value a name (and a colour, not used here). What the
//! names mean is [`crate::label_names`]'s business.

use crate::error::{Error, Result};

/// Label values with the names a file gives them, in file order.
pub type LabelNames = Vec<(u16, String)>;

/// Which tool's label list a text is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LabelListFormat {
    /// ITK-SNAP's label description file: `IDX R G B A VIS MSH "LABEL"` per line.
    ItkSnap,
    /// 3D Slicer's colour table (`.ctbl`, or a `.txt` colour file): `id name R G B A`.
    SlicerColors,
}

/// Tells an ITK-SNAP label description from a Slicer colour table by its first data
/// line (ITK-SNAP quotes its names, Slicer does not); None for neither.
pub fn sniff_label_list(text: &str) -> Option<LabelListFormat> {
    let line = data_lines(text).next()?.1;
    if line.contains('"') {
        Some(LabelListFormat::ItkSnap)
    } else if parse_slicer_line(line).is_ok() {
        Some(LabelListFormat::SlicerColors)
    } else {
        None
    }
}

/// Parses a label list of either format: `(label value, name)` in file order.
/// `origin` names the source in errors.
///
/// ```
/// use myoslice::io::parse_label_list;
/// let itk = "# ITK-SnAP Label Description File\n\
///     0 0 0 0 0 0 0 \"Clear Label\"\n\
///     3 200 40 40 1 1 1 \"Left semitendinosus\"\n";
/// let slicer = "# Color table\n0 Background 0 0 0 0\n3 Semitendinosus_L 200 40 40 255\n";
/// for text in [itk, slicer] {
///     let labels = parse_label_list(text, "example").unwrap();
///     assert_eq!(labels[1].0, 3);
/// }
/// ```
pub fn parse_label_list(text: &str, origin: &str) -> Result<LabelNames> {
    let format = sniff_label_list(text).ok_or_else(|| {
        Error::parse(
            origin,
            "neither an ITK-SNAP label description file (`IDX R G B A VIS MSH \"LABEL\"`) nor a \
             3D Slicer colour table (`id name R G B A`)",
        )
    })?;
    let parse = match format {
        LabelListFormat::ItkSnap => parse_itksnap_line,
        LabelListFormat::SlicerColors => parse_slicer_line,
    };
    let mut out: LabelNames = Vec::new();
    let mut seen = std::collections::BTreeMap::new();
    for (n, line) in data_lines(text) {
        let (id, name) =
            parse(line).map_err(|why| Error::parse(origin, format!("line {n}: {why}")))?;
        if let Some(prev) = seen.insert(id, out.len()).map(|i| &out[i].1) {
            return Err(Error::parse(
                origin,
                format!("line {n}: label {id} is defined twice ('{prev}' and '{name}')"),
            ));
        }
        out.push((id, name));
    }
    Ok(out)
}

/// Non-blank lines that are not comments, numbered from 1.
fn data_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'))
}

fn label_value(field: &str) -> std::result::Result<u16, String> {
    field
        .parse::<u16>()
        .map_err(|_| format!("label value '{field}' is not a whole number in 0..=65535"))
}

fn number(field: &str, what: &str) -> std::result::Result<(), String> {
    match field.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(()),
        _ => Err(format!("{what} '{field}' is not a number")),
    }
}

/// `IDX R G B A VIS MSH "LABEL"`: seven numbers, then the label in double quotes.
fn parse_itksnap_line(line: &str) -> std::result::Result<(u16, String), String> {
    let quote = line
        .find('"')
        .ok_or("no label name in double quotes after the seven numbers")?;
    let fields: Vec<&str> = line[..quote].split_whitespace().collect();
    if fields.len() != 7 {
        return Err(format!(
            "{} fields before the label name, not 7 (IDX R G B A VIS MSH)",
            fields.len()
        ));
    }
    let id = label_value(fields[0])?;
    for (f, what) in fields[1..]
        .iter()
        .zip(["red", "green", "blue", "alpha", "visibility", "mesh"])
    {
        number(f, what)?;
    }
    let rest = &line[quote + 1..];
    let end = rest
        .rfind('"')
        .ok_or("the label name's closing quote is missing")?;
    let name = rest[..end].trim();
    if name.is_empty() {
        return Err(format!("label {id} has an empty name"));
    }
    Ok((id, name.to_string()))
}

/// `id name R G B A`: the name is what lies between the value and the four colour
/// numbers (Slicer writes it without spaces, older files may have them).
fn parse_slicer_line(line: &str) -> std::result::Result<(u16, String), String> {
    let fields: Vec<&str> = line.split_whitespace().collect();
    if fields.len() < 6 {
        return Err(format!("{} fields, not `id name R G B A`", fields.len()));
    }
    let id = label_value(fields[0])?;
    let colours = &fields[fields.len() - 4..];
    for (f, what) in colours.iter().zip(["red", "green", "blue", "alpha"]) {
        number(f, what)?;
    }
    let name = fields[1..fields.len() - 4].join(" ");
    Ok((id, name))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_itk_snap_file_as_the_tool_writes_it_parses() {
        let text = "################################################\n\
# ITK-SnAP Label Description File\n\
# File format: \n\
# IDX   -R-  -G-  -B-  -A--  VIS MSH  LABEL\n\
################################################\n\
    0     0    0    0        0  0  0    \"Clear Label\"\n\
    1   255    0    0        1  1  1    \"Subcutaneous fat\"\n\
   39   102  205  170     0.75  1  1    \"M. semitendinosus (left)\"\n";
        assert_eq!(sniff_label_list(text), Some(LabelListFormat::ItkSnap));
        let l = parse_label_list(text, "t.txt").unwrap();
        assert_eq!(
            l,
            vec![
                (0, "Clear Label".into()),
                (1, "Subcutaneous fat".into()),
                (39, "M. semitendinosus (left)".into())
            ]
        );
    }

    #[test]
    fn a_slicer_colour_table_parses_with_or_without_spaces_in_names() {
        let text = "# Color table file /tmp/x.ctbl\n# 3 values\n0 Background 0 0 0 0\n\
                    2 Femur 241 214 145 255\n39 semi tendinosus 10 20 30 255\n";
        assert_eq!(sniff_label_list(text), Some(LabelListFormat::SlicerColors));
        let l = parse_label_list(text, "t.ctbl").unwrap();
        assert_eq!(l[1], (2, "Femur".into()));
        assert_eq!(l[2], (39, "semi tendinosus".into()));
    }

    #[test]
    fn bad_lines_are_refused_naming_the_line() {
        for (text, says) in [
            (
                "0 0 0 0 0 0 0 \"a\"\n70000 0 0 0 1 1 1 \"b\"\n",
                "line 2: label value '70000'",
            ),
            (
                "0 0 0 0 0 0 0 \"a\"\n1 0 0 0 1 1 \"b\"\n",
                "line 2: 6 fields",
            ),
            ("0 0 0 0 0 0 0 \"a\"\n1 0 0 0 1 1 1 \"b\n", "closing quote"),
            (
                "0 0 0 0 0 0 0 \"a\"\n0 0 0 0 1 1 1 \"b\"\n",
                "label 0 is defined twice",
            ),
            ("0 Background 0 0 0 0\n1 fat 0 0 x 0\n", "line 2: blue 'x'"),
            ("0 0 0 0 0 0 0 \"\"\n", "empty name"),
            ("hello world\n", "neither an ITK-SNAP"),
            ("", "neither an ITK-SNAP"),
        ] {
            let e = parse_label_list(text, "f").unwrap_err().to_string();
            assert!(e.contains(says), "{text:?}: {e}");
        }
    }
}
