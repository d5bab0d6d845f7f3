//! NRRD label volumes (`.nrrd`, `.nhdr` + data file), as 3D Slicer and ITK write them,
//! and Slicer segmentations (`.seg.nrrd`) with their segments' names.
//!
//! Read: integer voxel types up to 32 bits (values must fit a label, 0..=65535), raw or
//! gzip encoding, either byte order, data attached or in one detached file, `space
//! directions` / `space origin` in a left-posterior-superior or right-anterior-superior
//! space (turned into our right-anterior-superior millimetres), or plain `spacings`. A
//! segmentation's `Segment{N}_Name`, `_LabelValue` and `_Layer` fields name its labels;
//! with several layers (a 4-D array, layers first) a voxel takes the segment of the last
//! layer that labels it, and the labels are renumbered segment by segment (the rule is
//! reported in [`NrrdVolume::merge`]).

use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};

use super::{LabelNames, MAX_VOLUME_BYTES};
use crate::error::{Error, Result};
use crate::label_volume::LabelVolume;

/// A label volume read from NRRD, with the names a segmentation gives its labels.
#[derive(Debug, Clone, PartialEq)]
pub struct NrrdVolume {
    /// The voxels, in our frame.
    pub volume: LabelVolume,
    /// `(label, segment name)` of a Slicer segmentation, in segment order; None for a
    /// plain label map (its names come from a label table or colour table).
    pub segments: Option<LabelNames>,
    /// How several layers were merged into one label map, if they were.
    pub merge: Option<String>,
}

/// Reads a NRRD label volume (attached or detached data).
pub fn read_nrrd(path: impl AsRef<Path>) -> Result<NrrdVolume> {
    let path = path.as_ref();
    let raw = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_nrrd(&raw, path)
}

/// Parses NRRD bytes; `path` names the file in messages and locates a detached data file.
pub fn parse_nrrd(raw: &[u8], path: &Path) -> Result<NrrdVolume> {
    let err = |reason: String| Error::parse(path, reason);
    let h = Header::parse(raw).map_err(err)?;
    let payload: std::borrow::Cow<'_, [u8]> = match &h.data_file {
        None => raw.get(h.data_start..).unwrap_or_default().into(),
        Some(f) => read_detached(&path.parent().unwrap_or(Path::new(".")).join(f), &h)?.into(),
    };
    h.volume(&payload).map_err(err)
}

/// How much of a file [`detached_data_file`] reads for its header (a segmentation's
/// header names every segment: tens of kilobytes).
const HEADER_READ_BYTES: u64 = 1 << 20;

/// The detached data file the NRRD header at `path` names, if it names one (the header
/// alone is read); None too where `path` is not a readable NRRD header.
pub(crate) fn detached_data_file(path: &Path) -> Option<PathBuf> {
    let mut file = std::fs::File::open(path).ok()?;
    let mut head = Vec::new();
    // The magic line first: a NIfTI (or any other file) is read no further.
    (&mut file).take(8).read_to_end(&mut head).ok()?;
    if !is_nrrd(&head) {
        return None;
    }
    file.take(HEADER_READ_BYTES).read_to_end(&mut head).ok()?;
    let f = Header::parse(&head).ok()?.data_file?;
    Some(path.parent().unwrap_or(Path::new(".")).join(f))
}

/// A detached data file, read no further than the header's voxels can reach: a regular
/// file only (not `/dev/zero` or a pipe).
fn read_detached(p: &Path, h: &Header) -> Result<Vec<u8>> {
    let file = std::fs::File::open(p).map_err(|e| Error::io(p, e))?;
    let meta = file.metadata().map_err(|e| Error::io(p, e))?;
    if !meta.is_file() {
        return Err(Error::parse(p, "the NRRD data file is not a regular file"));
    }
    let limit = if h.gzip {
        MAX_VOLUME_BYTES
    } else {
        // The voxels, the bytes skipped, and room for skipped lines.
        h.voxel_bytes() + h.byte_skip as u64 + (h.line_skip as u64) * 4096
    };
    let mut out = Vec::new();
    file.take(limit)
        .read_to_end(&mut out)
        .map_err(|e| Error::io(p, e))?;
    Ok(out)
}

/// Whether bytes start like a NRRD file.
pub fn is_nrrd(raw: &[u8]) -> bool {
    raw.starts_with(b"NRRD000")
}

/// Voxel types a label volume may have.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Type {
    U8,
    I8,
    U16,
    I16,
    U32,
    I32,
}

impl Type {
    fn parse(s: &str) -> std::result::Result<Self, String> {
        Ok(match s {
            "uchar" | "unsigned char" | "uint8" | "uint8_t" => Type::U8,
            "signed char" | "int8" | "int8_t" | "char" => Type::I8,
            "ushort" | "unsigned short" | "unsigned short int" | "uint16" | "uint16_t" => Type::U16,
            "short" | "short int" | "signed short" | "signed short int" | "int16" | "int16_t" => {
                Type::I16
            }
            "uint" | "unsigned int" | "uint32" | "uint32_t" => Type::U32,
            "int" | "signed int" | "int32" | "int32_t" => Type::I32,
            other => {
                return Err(format!(
                    "voxel type '{other}' is not a label type (8 to 32-bit integers)"
                ));
            }
        })
    }

    fn bytes(self) -> usize {
        match self {
            Type::U8 | Type::I8 => 1,
            Type::U16 | Type::I16 => 2,
            Type::U32 | Type::I32 => 4,
        }
    }

    fn value(self, b: &[u8], big: bool) -> i64 {
        let mut a = [0u8; 4];
        let n = self.bytes();
        a[..n].copy_from_slice(&b[..n]);
        if big {
            a[..n].reverse();
        }
        match self {
            Type::U8 => i64::from(a[0]),
            Type::I8 => i64::from(a[0] as i8),
            Type::U16 => i64::from(u16::from_le_bytes([a[0], a[1]])),
            Type::I16 => i64::from(i16::from_le_bytes([a[0], a[1]])),
            Type::U32 => i64::from(u32::from_le_bytes(a)),
            Type::I32 => i64::from(i32::from_le_bytes(a)),
        }
    }
}

#[derive(Debug)]
struct Header {
    ty: Type,
    /// Sizes, fastest first; 3 spatial, after a layer axis for a 4-D segmentation.
    sizes: Vec<usize>,
    layers: usize,
    gzip: bool,
    big: bool,
    byte_skip: usize,
    line_skip: usize,
    /// Voxel-to-world affine (mm, right-anterior-superior).
    affine: [[f64; 4]; 3],
    data_file: Option<String>,
    data_start: usize,
    /// Segment index → key/value fields (`Segment3_Name` → (3, "Name")).
    segments: BTreeMap<usize, BTreeMap<String, String>>,
}

impl Header {
    fn parse(raw: &[u8]) -> std::result::Result<Self, String> {
        if !is_nrrd(raw) {
            return Err("not a NRRD file (no NRRD000x magic line)".into());
        }
        let mut fields: BTreeMap<String, String> = BTreeMap::new();
        let mut segments: BTreeMap<usize, BTreeMap<String, String>> = BTreeMap::new();
        let mut pos = 0;
        let mut first = true;
        let mut data_start = raw.len();
        while pos < raw.len() {
            let end = raw[pos..]
                .iter()
                .position(|&b| b == b'\n')
                .map_or(raw.len(), |e| pos + e);
            let line = std::str::from_utf8(&raw[pos..end])
                .map_err(|_| "the header is not text".to_string())?
                .trim_end_matches('\r');
            pos = end + 1;
            if first {
                first = false;
                continue;
            }
            if line.is_empty() {
                data_start = pos.min(raw.len());
                break;
            }
            if line.starts_with('#') {
                continue;
            }
            if let Some((k, v)) = line.split_once(":=") {
                if let Some((n, key)) = segment_key(k) {
                    segments.entry(n).or_default().insert(key, v.to_string());
                }
                continue;
            }
            let (k, v) = line
                .split_once(": ")
                .ok_or_else(|| format!("header line '{line}' is not `field: value`"))?;
            fields.insert(k.trim().to_ascii_lowercase(), v.trim().to_string());
        }
        let get = |k: &str| fields.get(k).map(String::as_str);
        let need = |k: &str| get(k).ok_or_else(|| format!("the header has no '{k}' field"));
        let ty = Type::parse(need("type")?)?;
        let dimension: usize = need("dimension")?
            .parse()
            .map_err(|_| "'dimension' is not a whole number".to_string())?;
        let sizes: Vec<usize> = need("sizes")?
            .split_whitespace()
            .map(|s| {
                s.parse::<usize>()
                    .map_err(|_| format!("size '{s}' is not a whole number"))
            })
            .collect::<std::result::Result<_, _>>()?;
        if sizes.len() != dimension || !(3..=4).contains(&dimension) {
            return Err(format!(
                "{} sizes for dimension {dimension}: a label volume has 3 axes (or 4, layers first)",
                sizes.len()
            ));
        }
        if sizes.contains(&0) {
            return Err(format!("sizes {sizes:?} have an empty axis"));
        }
        let layers = if dimension == 4 { sizes[0] } else { 1 };
        let voxels = sizes.iter().try_fold(1u64, |n, s| n.checked_mul(*s as u64));
        match voxels.and_then(|n| n.checked_mul(ty.bytes() as u64)) {
            Some(b) if b <= MAX_VOLUME_BYTES => {}
            _ => {
                return Err(format!(
                    "sizes {sizes:?} claim more than the {MAX_VOLUME_BYTES}-byte cap on a label volume"
                ));
            }
        }
        let gzip = match get("encoding").unwrap_or("raw") {
            "raw" => false,
            "gzip" | "gz" => true,
            other => return Err(format!("encoding '{other}' is not read (raw or gzip)")),
        };
        let big = match get("endian") {
            None | Some("little") => false,
            Some("big") => true,
            Some(other) => return Err(format!("endian '{other}' is neither little nor big")),
        };
        let byte_skip = match get("byte skip") {
            None => 0,
            Some(s) => s
                .parse()
                .map_err(|_| format!("byte skip '{s}' is not a whole number (-1 is not read)"))?,
        };
        let line_skip = match get("line skip") {
            None => 0,
            Some(s) => s
                .parse()
                .map_err(|_| format!("line skip '{s}' is not a whole number"))?,
        };
        if gzip && line_skip > 0 {
            return Err("line skip before gzip data is not read".into());
        }
        let data_file = get("data file").or(get("datafile")).map(str::to_string);
        if let Some(f) = &data_file
            && (f.starts_with("LIST") || f.split_whitespace().count() > 1)
        {
            return Err(format!("data file '{f}': only one detached file is read"));
        }
        let affine = affine(
            get("space"),
            get("space directions"),
            get("space origin"),
            get("spacings"),
            dimension,
        )?;
        if let Some(k) = get("kinds") {
            let kinds: Vec<&str> = k.split_whitespace().collect();
            let spatial = |k: &str| matches!(k, "domain" | "space");
            let ok = kinds.len() == dimension
                && kinds[..dimension - 3].iter().all(|k| !spatial(k))
                && kinds[dimension - 3..].iter().all(|k| spatial(k));
            if !ok {
                return Err(format!(
                    "kinds '{k}': three spatial axes (domain or space) expected, after a layer axis in 4-D"
                ));
            }
        }
        Ok(Self {
            ty,
            sizes,
            layers,
            gzip,
            big,
            byte_skip,
            line_skip,
            affine,
            data_file,
            data_start,
            segments,
        })
    }

    /// Bytes of voxel data the sizes and type claim (at most the cap, see [`Self::parse`]).
    fn voxel_bytes(&self) -> u64 {
        self.sizes.iter().map(|s| *s as u64).product::<u64>() * self.ty.bytes() as u64
    }

    fn volume(&self, payload: &[u8]) -> std::result::Result<NrrdVolume, String> {
        let mut body = payload;
        for _ in 0..self.line_skip {
            let end = body
                .iter()
                .position(|&b| b == b'\n')
                .ok_or("line skip reaches past the data")?;
            body = &body[end + 1..];
        }
        let want = self.voxel_bytes() as usize;
        // Byte skip counts in the data as stored after decompression.
        let bytes: std::borrow::Cow<'_, [u8]> = if self.gzip {
            let mut out = Vec::new();
            flate2::read::MultiGzDecoder::new(body)
                .take((want + self.byte_skip) as u64)
                .read_to_end(&mut out)
                .map_err(|e| format!("gzip data is corrupt or truncated ({e})"))?;
            if self.byte_skip > out.len() {
                return Err("byte skip reaches past the data".into());
            }
            out.drain(..self.byte_skip);
            out.into()
        } else {
            body.get(self.byte_skip..)
                .ok_or("byte skip reaches past the data")?
                .into()
        };
        if bytes.len() < want {
            return Err(format!(
                "{} bytes of voxel data for sizes {:?}, which need {want}",
                bytes.len(),
                self.sizes
            ));
        }
        let value = |i: usize| self.ty.value(&bytes[i * self.ty.bytes()..], self.big);
        let dims = {
            let s = &self.sizes[self.sizes.len() - 3..];
            [s[0], s[1], s[2]]
        };
        let cells = dims[0] * dims[1] * dims[2];
        let layered = self.layers > 1 || !self.segments.is_empty();
        let (data, segments, merge) = if layered {
            self.merge_layers(cells, value)?
        } else {
            let mut data = Vec::with_capacity(cells);
            for i in 0..cells {
                data.push(label(value(i), i)?);
            }
            (data, None, None)
        };
        let volume = LabelVolume::new(dims, self.affine, data).map_err(|e| e.to_string())?;
        Ok(NrrdVolume {
            volume,
            segments,
            merge,
        })
    }

    /// A segmentation's layers as one label map: segment `s` (in the header's order)
    /// becomes label `s + 1`; a voxel labelled in several layers takes the last one.
    fn merge_layers(
        &self,
        cells: usize,
        value: impl Fn(usize) -> i64,
    ) -> std::result::Result<Merged, String> {
        let mut by_value: BTreeMap<(usize, i64), u16> = BTreeMap::new();
        // Voxels of no segment: the background.
        let mut names = vec![(0u16, "Background".to_string())];
        // Segmentations before layers were shared (Slicer 4.10) store each segment in a
        // layer of its own, with no `_Layer` or `_LabelValue`.
        let legacy = self.layers > 1
            && self.layers == self.segments.len()
            && self.segments.values().all(|f| !f.contains_key("Layer"));
        for (k, (n, f)) in self.segments.iter().enumerate() {
            let name = f
                .get("Name")
                .cloned()
                .ok_or_else(|| format!("segment {n} has no Segment{n}_Name"))?;
            let parse = |key: &str, default: i64| -> std::result::Result<i64, String> {
                f.get(key).map_or(Ok(default), |v| {
                    v.trim()
                        .parse()
                        .map_err(|_| format!("Segment{n}_{key} '{v}' is not a whole number"))
                })
            };
            let value = parse("LabelValue", 1)?;
            let layer = parse("Layer", if legacy { k as i64 } else { 0 })?;
            if layer < 0 || layer as usize >= self.layers {
                return Err(format!(
                    "segment {n} '{name}' lies in layer {layer}, of {} layers",
                    self.layers
                ));
            }
            let id = u16::try_from(k + 1).map_err(|_| "more than 65535 segments".to_string())?;
            if by_value.insert((layer as usize, value), id).is_some() {
                return Err(format!(
                    "segment {n} '{name}': label value {value} of layer {layer} is another segment's"
                ));
            }
            names.push((id, name));
        }
        if names.len() == 1 {
            return Err(format!(
                "{} layers but no Segment{{N}}_Name fields: not a segmentation to merge",
                self.layers
            ));
        }
        // Label value → label, per layer (0: no segment; the values are small).
        let used = by_value.keys().map(|k| k.0 + 1).max().unwrap_or(0);
        let mut lut = vec![[0u16; 256]; used];
        for (&(layer, v), &id) in &by_value {
            if let Ok(v) = u8::try_from(v) {
                lut[layer][usize::from(v)] = id;
            }
        }
        let mut data = vec![0u16; cells];
        for (c, d) in data.iter_mut().enumerate() {
            for layer in 0..self.layers {
                let v = value(c * self.layers + layer);
                if v == 0 {
                    continue;
                }
                let fast = u8::try_from(v)
                    .ok()
                    .and_then(|b| lut.get(layer).map(|t| t[usize::from(b)]));
                let id = match fast {
                    Some(id) if id != 0 => Some(id),
                    _ => by_value.get(&(layer, v)).copied(),
                };
                *d = id.ok_or_else(|| {
                    format!("voxel {c}: value {v} of layer {layer} is no segment's label value")
                })?;
            }
        }
        let merge = (self.layers > 1).then(|| {
            format!(
                "{} layers merged: each segment is its own label (1..={}), and a voxel in \
                 segments of several layers takes the last layer's",
                self.layers,
                names.len() - 1
            )
        });
        Ok((data, Some(names), merge))
    }
}

/// Merged voxels, segment names and the rule applied.
type Merged = (Vec<u16>, Option<LabelNames>, Option<String>);

fn label(v: i64, i: usize) -> std::result::Result<u16, String> {
    u16::try_from(v).map_err(|_| format!("voxel {i} holds {v}, not a label in 0..=65535"))
}

/// `Segment12_LabelValue` → (12, "LabelValue").
fn segment_key(k: &str) -> Option<(usize, String)> {
    let rest = k.trim().strip_prefix("Segment")?;
    let (n, key) = rest.split_once('_')?;
    Some((n.parse().ok()?, key.to_string()))
}

/// The voxel-to-world affine (mm, right-anterior-superior) from the header's geometry.
fn affine(
    space: Option<&str>,
    directions: Option<&str>,
    origin: Option<&str>,
    spacings: Option<&str>,
    dimension: usize,
) -> std::result::Result<[[f64; 4]; 3], String> {
    // Left-posterior-superior flips x and y into ours; right-anterior-superior is ours.
    let flip = match space.map(|s| s.trim().to_ascii_lowercase()) {
        None => [1.0, 1.0, 1.0],
        Some(s) if s == "right-anterior-superior" || s == "ras" => [1.0, 1.0, 1.0],
        Some(s) if s == "left-posterior-superior" || s == "lps" => [-1.0, -1.0, 1.0],
        Some(s) => {
            return Err(format!(
                "space '{s}' is not read (left-posterior-superior or right-anterior-superior)"
            ));
        }
    };
    let mut a = [[0.0f64; 4]; 3];
    match (directions, spacings) {
        (Some(d), _) => {
            let vectors: Vec<&str> = d.split_whitespace().collect();
            let layer_axes = dimension.saturating_sub(3);
            let ok = vectors.len() == dimension
                && vectors[..layer_axes].iter().all(|v| *v == "none")
                && vectors[layer_axes..].iter().all(|v| *v != "none");
            if !ok {
                return Err(format!(
                    "space directions '{d}': 3 vectors expected (after 'none' for a layer axis in 4-D)"
                ));
            }
            let spatial = &vectors[layer_axes..];
            for (c, v) in spatial.iter().enumerate() {
                let x = vector(v)?;
                for r in 0..3 {
                    a[r][c] = x[r] * flip[r];
                }
            }
        }
        (None, Some(s)) => {
            let tokens: Vec<&str> = s.split_whitespace().collect();
            let layer_axes = dimension.saturating_sub(3);
            if tokens.len() != dimension
                || !tokens[..layer_axes]
                    .iter()
                    .all(|t| t.eq_ignore_ascii_case("nan"))
            {
                return Err(format!(
                    "spacings '{s}': 3 spatial spacings expected (after NaN for a layer axis in 4-D)"
                ));
            }
            let v: Vec<f64> = tokens[layer_axes..]
                .iter()
                .map(|t| match t.parse::<f64>() {
                    Ok(x) if x.is_finite() && x != 0.0 => Ok(x),
                    _ => Err(format!("spacing '{t}' is not a non-zero number")),
                })
                .collect::<std::result::Result<_, _>>()?;
            for r in 0..3 {
                a[r][r] = v[r];
            }
        }
        (None, None) => {
            for (r, row) in a.iter_mut().enumerate() {
                row[r] = 1.0;
            }
        }
    }
    if let Some(o) = origin {
        let x = vector(o)?;
        for r in 0..3 {
            a[r][3] = x[r] * flip[r];
        }
    }
    if a.iter().flatten().any(|v| !v.is_finite()) {
        return Err("the voxel-to-world transform is not finite".into());
    }
    Ok(a)
}

/// `(x,y,z)` → three numbers.
fn vector(s: &str) -> std::result::Result<[f64; 3], String> {
    let inner = s
        .trim()
        .strip_prefix('(')
        .and_then(|t| t.strip_suffix(')'))
        .ok_or_else(|| format!("'{s}' is not a vector `(x,y,z)`"))?;
    let v: Vec<f64> = inner
        .split(',')
        .map(|t| {
            t.trim()
                .parse::<f64>()
                .map_err(|_| format!("'{t}' in '{s}' is not a number"))
        })
        .collect::<std::result::Result<_, _>>()?;
    <[f64; 3]>::try_from(v).map_err(|_| format!("'{s}' does not have 3 numbers"))
}
