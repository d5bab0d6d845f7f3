//! Generating the built-in phantom volume from its definition.

use std::f64::consts::TAU;
use std::sync::OnceLock;

use crate::par::*;

use super::definition::{Level, PhantomDefinition};
use crate::error::{Error, Result};
use crate::label_table::{Label, LabelTable, TissueKind};
use crate::label_volume::LabelVolume;

/// The embedded definition (`assets/phantom/leg.toml`), measured on the Visible Human leg.
pub const LEG_DEFINITION: &str = include_str!("../../../../assets/phantom/leg.toml");

/// The built-in left lower limb, pelvis to ankle, as a label volume that needs no files.
///
/// ```
/// use myoslice::phantom::Phantom;
/// let (volume, table) = Phantom { voxel_mm: Some(4.0) }.generate()?;
/// assert!(table.by_name("semitendinosus").is_ok());
/// assert!(volume.dims()[2] > 100);
/// # Ok::<(), myoslice::Error>(())
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Phantom {
    /// Voxel edge (mm); `None` keeps the definition's 1 mm.
    pub voxel_mm: Option<f64>,
}

/// The parsed built-in definition.
pub fn leg_definition() -> Result<&'static PhantomDefinition> {
    static DEF: OnceLock<std::result::Result<PhantomDefinition, String>> = OnceLock::new();
    DEF.get_or_init(|| {
        PhantomDefinition::from_toml_str(LEG_DEFINITION, "assets/phantom/leg.toml")
            .map_err(|e| e.to_string())
    })
    .as_ref()
    .map_err(|e| Error::Build(format!("built-in phantom definition is invalid: {e}")))
}

impl Phantom {
    /// Generates the built-in phantom.
    pub fn generate(&self) -> Result<(LabelVolume, LabelTable)> {
        generate(leg_definition()?, self.voxel_mm)
    }
}

/// The label table of a definition: background 0, fat 1, then its structures.
pub fn definition_table(def: &PhantomDefinition) -> Result<LabelTable> {
    let mut labels = vec![
        Label {
            id: 0,
            name: "background".into(),
            kind: TissueKind::Background,
            origin: None,
            insertion: None,
        },
        Label {
            id: 1,
            name: "fat".into(),
            kind: TissueKind::Fat,
            origin: None,
            insertion: None,
        },
    ];
    labels.extend(def.structure.iter().map(|s| Label {
        id: s.id,
        name: s.name.clone(),
        kind: s.kind,
        origin: s.origin.clone(),
        insertion: s.insertion.clone(),
    }));
    LabelTable::new(labels)
}

/// Rasterises a definition at `voxel_mm` (default: its own). Bones win over muscles;
/// where muscles overlap, the one the voxel lies deeper in wins; the rest of the inside of
/// the skin is fat.
pub fn generate(
    def: &PhantomDefinition,
    voxel_mm: Option<f64>,
) -> Result<(LabelVolume, LabelTable)> {
    let vox = voxel_mm.unwrap_or(def.phantom.voxel_mm);
    if !(vox.is_finite() && (0.25..=20.0).contains(&vox)) {
        return Err(Error::invalid(
            "voxel_mm",
            vox,
            "expected a voxel size in [0.25, 20] mm",
        ));
    }
    let table = definition_table(def)?;
    let [lo, hi] = def.phantom.extent_mm;
    let dims = [0, 1, 2].map(|a| ((hi[a] - lo[a]) / vox).floor() as usize + 1);
    let m = def.phantom.angles;
    let slices: Vec<Vec<u16>> = (0..dims[2])
        .into_par_iter()
        .map(|k| {
            let z = lo[2] + k as f64 * vox;
            let n = dims[0] * dims[1];
            let mut label = vec![0u16; n];
            let mut score = vec![f32::NEG_INFINITY; n];
            let mut paint = |levels: &[Level], id: u16, bonus: f64| {
                let Some(l) = interpolate(levels, z) else {
                    return;
                };
                raster(&l, m, lo, vox, dims, |p, s| {
                    let s = (s + bonus) as f32;
                    if s > score[p] {
                        score[p] = s;
                        label[p] = id;
                    }
                });
            };
            paint(&def.skin, 1, -1e6);
            for st in &def.structure {
                let bonus = if st.kind == TissueKind::Bone {
                    1e6
                } else {
                    0.0
                };
                paint(&st.levels, st.id, bonus);
            }
            label
        })
        .collect();
    let data: Vec<u16> = slices.into_iter().flatten().collect();
    let volume = LabelVolume::axis_aligned(dims, [vox; 3], lo, data)?;
    Ok((volume, table))
}

/// The outline at height `z`, interpolated between the bracketing levels.
fn interpolate(levels: &[Level], z: f64) -> Option<Level> {
    let first = levels.first()?;
    let last = levels.last()?;
    if z < first[0] - 0.5 || z > last[0] + 0.5 {
        return None;
    }
    let i = levels.partition_point(|l| l[0] <= z);
    if i == 0 {
        return Some(first.clone());
    }
    if i == levels.len() {
        return Some(last.clone());
    }
    let (a, b) = (&levels[i - 1], &levels[i]);
    let t = (z - a[0]) / (b[0] - a[0]);
    // An empty side (structure absent) must not drag the centre: keep the other's centre.
    let empty = |l: &Level| l[3..].iter().all(|&r| r == 0.0);
    let mut out: Level = a.iter().zip(b).map(|(x, y)| x + t * (y - x)).collect();
    if empty(a) && !empty(b) {
        out[1] = b[1];
        out[2] = b[2];
    } else if empty(b) && !empty(a) {
        out[1] = a[1];
        out[2] = a[2];
    }
    Some(out)
}

/// Calls `f(pixel index, depth mm)` for every pixel inside an outline.
fn raster(
    l: &Level,
    m: usize,
    lo: [f64; 3],
    vox: f64,
    dims: [usize; 3],
    mut f: impl FnMut(usize, f64),
) {
    let (cx, cy) = (l[1], l[2]);
    let r_in = &l[3..3 + m];
    let r_out = &l[3 + m..3 + 2 * m];
    let rmax = r_out.iter().copied().fold(0.0, f64::max);
    if rmax <= 0.0 {
        return;
    }
    let u0 = (((cx - rmax - lo[0]) / vox).floor().max(0.0)) as usize;
    let u1 = ((((cx + rmax - lo[0]) / vox).ceil()).max(0.0) as usize).min(dims[0] - 1);
    let v0 = (((cy - rmax - lo[1]) / vox).floor().max(0.0)) as usize;
    let v1 = ((((cy + rmax - lo[1]) / vox).ceil()).max(0.0) as usize).min(dims[1] - 1);
    for v in v0..=v1 {
        let y = lo[1] + v as f64 * vox - cy;
        for u in u0..=u1 {
            let x = lo[0] + u as f64 * vox - cx;
            let r = (x * x + y * y).sqrt();
            if r > rmax {
                continue;
            }
            let fa = y.atan2(x).rem_euclid(TAU) / TAU * m as f64;
            let a0 = (fa.floor() as usize) % m;
            let a1 = (a0 + 1) % m;
            let t = fa - fa.floor();
            let ri = r_in[a0] + t * (r_in[a1] - r_in[a0]);
            let ro = r_out[a0] + t * (r_out[a1] - r_out[a0]);
            if ro > ri && r >= ri && r <= ro {
                f(u + dims[0] * v, (r - ri).min(ro - r));
            }
        }
    }
}
