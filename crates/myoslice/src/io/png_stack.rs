//! Label volumes from a folder of PNG slices with a TOML manifest.
//!
//! The folder holds one PNG per slice, read in name order from inferior to superior, and
//! a manifest (default name `manifest.toml`):
//!
//! ```toml
//! pixel_size_mm = [1.0, 1.0]     # column, row pixel size
//! slice_interval_mm = 1.0
//! origin_mm = [0.0, 0.0, 0.0]    # optional: world position of the first pixel of slice 0
//! column_axis = "+x"             # optional: world axis along increasing column (+x, -x, +y, -y)
//! row_axis = "-y"                # optional: image rows run from anterior (top) to posterior
//! labels_file = "labels.json"    # or an inline [labels] table in the same format
//!
//! [colors]                       # optional, for RGB(A) images: colour -> label id
//! "#ff0000" = 10
//! ```
//!
//! Grey-scale (8 or 16 bit) and indexed images carry label ids directly; RGB(A) images
//! need the `[colors]` map.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::error::{Error, Result};
use crate::label_table::LabelTable;
use crate::label_volume::LabelVolume;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Manifest {
    pixel_size_mm: PixelSize,
    slice_interval_mm: f64,
    #[serde(default)]
    origin_mm: Option<[f64; 3]>,
    #[serde(default)]
    column_axis: Option<String>,
    #[serde(default)]
    row_axis: Option<String>,
    #[serde(default)]
    labels_file: Option<PathBuf>,
    #[serde(default)]
    labels: Option<toml::Table>,
    #[serde(default)]
    colors: BTreeMap<String, u16>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum PixelSize {
    One(f64),
    Two([f64; 2]),
}

fn axis(spec: Option<&str>, default: [f64; 3], key: &str, path: &Path) -> Result<[f64; 3]> {
    Ok(match spec {
        None => default,
        Some("+x") | Some("x") => [1.0, 0.0, 0.0],
        Some("-x") => [-1.0, 0.0, 0.0],
        Some("+y") | Some("y") => [0.0, 1.0, 0.0],
        Some("-y") => [0.0, -1.0, 0.0],
        Some(other) => {
            return Err(Error::Parse {
                path: path.into(),
                reason: format!("{key} = '{other}': expected one of +x, -x, +y, -y"),
            });
        }
    })
}

fn parse_color(s: &str) -> Option<[u8; 3]> {
    let h = s.strip_prefix('#')?;
    if h.len() != 6 {
        return None;
    }
    let v = u32::from_str_radix(h, 16).ok()?;
    Some([(v >> 16) as u8, (v >> 8) as u8, v as u8])
}

/// The `.png` slices of `folder`, in reading order (by name).
fn slice_files(folder: &Path) -> Result<Vec<PathBuf>> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(folder)
        .map_err(|e| Error::io(folder, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")))
        .collect();
    files.sort();
    Ok(files)
}

/// Every file reading the stack touches: its manifest, the label file the manifest
/// names, and its slices. Only the manifest is read; what cannot be looked at is left
/// out (reading the stack says why).
pub(crate) fn stack_files(folder: &Path, manifest: &Path) -> Vec<PathBuf> {
    let mut files = vec![manifest.to_path_buf()];
    let labels_file = std::fs::read_to_string(manifest)
        .ok()
        .and_then(|text| toml::from_str::<Manifest>(&text).ok())
        .and_then(|m| m.labels_file);
    if let Some(f) = labels_file {
        files.push(manifest.parent().unwrap_or(folder).join(f));
    }
    files.extend(slice_files(folder).unwrap_or_default());
    files
}

/// Reads a PNG slice folder; `manifest` defaults to `folder/manifest.toml`.
pub fn read_png_stack(
    folder: impl AsRef<Path>,
    manifest: Option<&Path>,
) -> Result<(LabelVolume, LabelTable)> {
    read_png_stack_with(folder, manifest, crate::label_names::Unmapped::Error)
}

/// [`read_png_stack`], a tool's label list named by the manifest's `labels_file` read as
/// `mapping` says (the user's names file, what becomes of unknown names).
pub fn read_png_stack_with(
    folder: impl AsRef<Path>,
    manifest: Option<&Path>,
    mapping: impl Into<crate::label_mapping::LabelMapping>,
) -> Result<(LabelVolume, LabelTable)> {
    let folder = folder.as_ref();
    let mpath = manifest.map_or_else(|| folder.join("manifest.toml"), Path::to_path_buf);
    let text = std::fs::read_to_string(&mpath).map_err(|e| Error::io(&mpath, e))?;
    let m: Manifest = toml::from_str(&text).map_err(|e| Error::Parse {
        path: mpath.clone(),
        reason: e.to_string(),
    })?;
    let table = match (&m.labels_file, &m.labels) {
        (Some(f), None) => {
            LabelTable::from_path_with(mpath.parent().unwrap_or(folder).join(f), mapping)?
        }
        (None, Some(t)) => {
            let mut wrap = toml::Table::new();
            wrap.insert("labels".into(), toml::Value::Table(t.clone()));
            LabelTable::from_toml_str(&wrap.to_string(), &mpath.display().to_string())?
        }
        _ => {
            return Err(Error::Parse {
                path: mpath,
                reason: "give exactly one of labels_file or an inline [labels] table".into(),
            });
        }
    };
    let (px, py) = match m.pixel_size_mm {
        PixelSize::One(v) => (v, v),
        PixelSize::Two([a, b]) => (a, b),
    };
    for (k, v) in [
        ("pixel_size_mm", px),
        ("pixel_size_mm", py),
        ("slice_interval_mm", m.slice_interval_mm),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::Parse {
                path: mpath,
                reason: format!("{k} = {v}: expected a finite value > 0"),
            });
        }
    }
    let mut colors = BTreeMap::new();
    for (k, id) in &m.colors {
        let c = parse_color(k).ok_or_else(|| Error::Parse {
            path: mpath.clone(),
            reason: format!("colour key '{k}' is not of the form \"#rrggbb\""),
        })?;
        colors.insert(c, *id);
    }
    let files = slice_files(folder)?;
    if files.is_empty() {
        return Err(Error::Png {
            path: folder.into(),
            reason: "no .png slices in the folder".into(),
        });
    }
    let mut dims: Option<(u32, u32)> = None;
    let mut data = Vec::new();
    for f in &files {
        let (w, h, labels) = read_png_labels(f, &colors)?;
        match dims {
            None => dims = Some((w, h)),
            Some((w0, h0)) if (w0, h0) != (w, h) => {
                return Err(Error::Png {
                    path: f.clone(),
                    reason: format!("slice is {w}x{h} pixels but the first slice is {w0}x{h0}"),
                });
            }
            _ => {}
        }
        data.extend(labels);
    }
    let (w, h) = dims.unwrap_or((0, 0));
    let cx = axis(
        m.column_axis.as_deref(),
        [1.0, 0.0, 0.0],
        "column_axis",
        &mpath,
    )?;
    let ry = axis(m.row_axis.as_deref(), [0.0, -1.0, 0.0], "row_axis", &mpath)?;
    if cx == ry || cx == ry.map(|v| -v) {
        return Err(Error::Parse {
            path: mpath,
            reason: "column_axis and row_axis must be different axes".into(),
        });
    }
    let o = m.origin_mm.unwrap_or([0.0; 3]);
    let mut affine = [[0.0; 4]; 3];
    for r in 0..3 {
        affine[r][0] = cx[r] * px;
        affine[r][1] = ry[r] * py;
        affine[r][3] = o[r];
    }
    affine[2][2] = m.slice_interval_mm;
    let volume = LabelVolume::new([w as usize, h as usize, files.len()], affine, data)?;
    volume.check_labels(&table)?;
    Ok((volume, table))
}

/// Most bytes one decoded PNG slice may take (512 MiB: an 8192 × 8192 16-bit RGBA
/// image), checked against the image's header before the pixels are allocated.
pub const MAX_SLICE_BYTES: u64 = 512 << 20;

fn read_png_labels(path: &Path, colors: &BTreeMap<[u8; 3], u16>) -> Result<(u32, u32, Vec<u16>)> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    decode_png_labels(&bytes, path, colors)
}

/// The labels of one PNG slice (`path` only names it in messages): grey values are label
/// ids, colours are looked up in `colors`. Returns width, height and the labels, rows
/// first.
pub fn decode_png_labels(
    bytes: &[u8],
    path: &Path,
    colors: &BTreeMap<[u8; 3], u16>,
) -> Result<(u32, u32, Vec<u16>)> {
    let perr = |reason: String| Error::Png {
        path: path.into(),
        reason,
    };
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = decoder.read_info().map_err(|e| perr(e.to_string()))?;
    let size = reader
        .output_buffer_size()
        .filter(|s| *s as u64 <= MAX_SLICE_BYTES)
        .ok_or_else(|| {
            let i = reader.info();
            perr(format!(
                "a {}x{} image needs more than the {MAX_SLICE_BYTES}-byte cap on one slice",
                i.width, i.height
            ))
        })?;
    // What the decoder will write, checked before the pixels are allocated.
    let (color_type, bit_depth) = reader.output_color_type();
    if !matches!(bit_depth, png::BitDepth::Eight | png::BitDepth::Sixteen) {
        return Err(perr(format!(
            "{bit_depth:?}-bit images are not supported; use 8 or 16 bit"
        )));
    }
    let ch = match color_type {
        png::ColorType::Grayscale | png::ColorType::Indexed => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
    };
    let wide = bit_depth == png::BitDepth::Sixteen;
    let mut buf = vec![0u8; size];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| perr(e.to_string()))?;
    let (w, h) = (info.width, info.height);
    let n = w as usize * h as usize;
    let bpp = ch * if wide { 2 } else { 1 };
    let mut out = Vec::with_capacity(n);
    for row in 0..h as usize {
        let start = row * info.line_size;
        let line = buf
            .get(start..start + w as usize * bpp)
            .ok_or_else(|| perr(format!("row {row} is shorter than {w} pixels")))?;
        for px in line.chunks_exact(bpp) {
            let sample = |c: usize| -> u16 {
                if wide {
                    u16::from_be_bytes([px[2 * c], px[2 * c + 1]])
                } else {
                    u16::from(px[c])
                }
            };
            let id = if ch <= 2 {
                sample(0)
            } else {
                let rgb = [sample(0), sample(1), sample(2)]
                    .map(|v| if wide { (v >> 8) as u8 } else { v as u8 });
                *colors.get(&rgb).ok_or_else(|| {
                    perr(format!(
                        "colour #{:02x}{:02x}{:02x} at row {row} is not in the manifest's [colors] map",
                        rgb[0], rgb[1], rgb[2]
                    ))
                })?
            };
            out.push(id);
        }
    }
    Ok((w, h, out))
}

/// Writes one grey-scale label slice (8-bit when every id fits, else 16-bit).
pub fn write_png_labels(path: &Path, width: u32, height: u32, labels: &[u16]) -> Result<()> {
    let file = std::fs::File::create(path).map_err(|e| Error::write(path, e))?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), width, height);
    enc.set_color(png::ColorType::Grayscale);
    let wide = labels.iter().any(|&v| v > 255);
    enc.set_depth(if wide {
        png::BitDepth::Sixteen
    } else {
        png::BitDepth::Eight
    });
    let bytes: Vec<u8> = if wide {
        labels.iter().flat_map(|v| v.to_be_bytes()).collect()
    } else {
        labels.iter().map(|&v| v as u8).collect()
    };
    let perr = |e: png::EncodingError| Error::Png {
        path: path.into(),
        reason: e.to_string(),
    };
    let mut w = enc.write_header().map_err(perr)?;
    w.write_image_data(&bytes).map_err(perr)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("myoslice-png-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    const MANIFEST: &str = r#"
pixel_size_mm = 0.5
slice_interval_mm = 2.0
[labels.0]
name = "background"
kind = "background"
[labels.2]
name = "femur"
kind = "bone"
"#;

    #[test]
    fn a_png_stack_loads_with_its_geometry() {
        let d = tmp("ok");
        std::fs::write(d.join("manifest.toml"), MANIFEST).unwrap();
        for s in 0..3 {
            let labels: Vec<u16> = (0..12).map(|i| if i == s + 4 { 2 } else { 0 }).collect();
            write_png_labels(&d.join(format!("s{s:03}.png")), 4, 3, &labels).unwrap();
        }
        let (v, t) = read_png_stack(&d, None).unwrap();
        assert_eq!(v.dims(), [4, 3, 3]);
        assert_eq!(v.get(0, 1, 0), 2);
        assert_eq!(v.get(2, 1, 2), 2);
        assert_eq!(v.spacing_mm(), [0.5, 0.5, 2.0]);
        assert_eq!(t.labels().len(), 2);
        std::fs::remove_dir_all(&d).ok();
    }

    #[test]
    fn a_stacks_input_files_are_its_manifest_label_file_and_slices() {
        let d = tmp("files");
        std::fs::write(
            d.join("manifest.toml"),
            "pixel_size_mm = 1\nslice_interval_mm = 1\nlabels_file = \"labels.json\"\n",
        )
        .unwrap();
        for name in ["b.png", "a.PNG", "notes.txt"] {
            std::fs::write(d.join(name), b"").unwrap();
        }
        assert_eq!(
            crate::io::input_files(&d),
            ["manifest.toml", "labels.json", "a.PNG", "b.png"].map(|f| d.join(f))
        );
        // Given by its manifest, the same.
        assert_eq!(
            crate::io::input_files(d.join("manifest.toml")),
            crate::io::input_files(&d)
        );
        std::fs::remove_dir_all(&d).ok();
    }

    #[test]
    fn a_slice_of_the_wrong_size_or_an_unknown_label_is_an_error() {
        let d = tmp("bad");
        std::fs::write(d.join("manifest.toml"), MANIFEST).unwrap();
        write_png_labels(&d.join("a.png"), 4, 3, &[0; 12]).unwrap();
        write_png_labels(&d.join("b.png"), 5, 3, &[0; 15]).unwrap();
        let e = read_png_stack(&d, None).unwrap_err().to_string();
        assert!(e.contains("b.png") && e.contains("5x3"), "{e}");
        std::fs::remove_file(d.join("b.png")).unwrap();
        write_png_labels(&d.join("b.png"), 4, 3, &[7; 12]).unwrap();
        let e = read_png_stack(&d, None).unwrap_err().to_string();
        assert!(e.contains("label 7"), "{e}");
        std::fs::write(d.join("b.png"), b"not a png").unwrap();
        let e = read_png_stack(&d, None).unwrap_err().to_string();
        assert!(e.contains("b.png"), "{e}");
        std::fs::write(
            d.join("manifest.toml"),
            "pixel_size_mm = 1\nslice_interval_mm = 1\nbogus = 3\n",
        )
        .unwrap();
        let e = read_png_stack(&d, None).unwrap_err().to_string();
        assert!(e.contains("bogus"), "{e}");
        std::fs::remove_dir_all(&d).ok();
    }
}
