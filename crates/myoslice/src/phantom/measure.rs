//! Measuring a phantom definition from a labelled volume (the Visible Human leg).

use std::f64::consts::TAU;

use super::definition::{Level, PhantomDefinition, PhantomHeader, PhantomStructure};
use crate::error::{Error, Result};
use crate::label_table::{LabelTable, TissueKind};
use crate::label_volume::LabelVolume;

/// Measures outlines every `level_mm` (and at each structure's ends) with `angles` rays.
/// Requires an axis-aligned volume.
pub fn measure_phantom(
    volume: &LabelVolume,
    table: &LabelTable,
    level_mm: f64,
    angles: usize,
    source: &str,
) -> Result<PhantomDefinition> {
    let a = volume.affine();
    for (r, row) in a.iter().enumerate() {
        for (c, v) in row.iter().take(3).enumerate() {
            if r != c && v.abs() > 1e-9 {
                return Err(Error::Build(
                    "phantom measurement needs an axis-aligned volume".into(),
                ));
            }
        }
    }
    let sp = volume.spacing_mm();
    let [nx, ny, nz] = volume.dims();
    let origin = [a[0][3], a[1][3], a[2][3]];
    let step = ((level_mm / sp[2]).round() as usize).max(1);
    let kinds = table.kind_lut();
    let levels_for = |is_in: &dyn Fn(u16) -> bool| -> Vec<Level> {
        let present: Vec<usize> = (0..nz)
            .filter(|&k| volume.slice(k).iter().any(|&l| is_in(l)))
            .collect();
        let (Some(&k0), Some(&k1)) = (present.first(), present.last()) else {
            return Vec::new();
        };
        let mut ks: Vec<usize> = (k0..=k1).step_by(step).collect();
        if ks.last() != Some(&k1) {
            ks.push(k1);
        }
        ks.iter()
            .map(|&k| measure_level(volume.slice(k), nx, ny, sp, origin, k, angles, is_in))
            .collect()
    };
    let skin = levels_for(&|l| {
        kinds
            .get(l as usize)
            .copied()
            .flatten()
            .is_some_and(|k| k != TissueKind::Background)
    });
    let mut structure = Vec::new();
    for l in table.labels() {
        if !matches!(l.kind, TissueKind::Bone | TissueKind::Muscle) {
            continue;
        }
        let id = l.id;
        let levels = levels_for(&|v| v == id);
        if levels.is_empty() {
            continue;
        }
        structure.push(PhantomStructure {
            id,
            name: l.name.clone(),
            kind: l.kind,
            origin: l.origin.clone(),
            insertion: l.insertion.clone(),
            levels,
        });
    }
    Ok(PhantomDefinition {
        phantom: PhantomHeader {
            source: source.to_string(),
            angles,
            voxel_mm: sp[0],
            extent_mm: [
                origin,
                [
                    origin[0] + (nx - 1) as f64 * sp[0],
                    origin[1] + (ny - 1) as f64 * sp[1],
                    origin[2] + (nz - 1) as f64 * sp[2],
                ],
            ],
        },
        skin,
        structure,
    })
}

#[allow(clippy::too_many_arguments)]
fn measure_level(
    slice: &[u16],
    nx: usize,
    ny: usize,
    sp: [f64; 3],
    origin: [f64; 3],
    k: usize,
    angles: usize,
    is_in: &dyn Fn(u16) -> bool,
) -> Level {
    let z = origin[2] + k as f64 * sp[2];
    let (mut n, mut sx, mut sy) = (0.0, 0.0, 0.0);
    for v in 0..ny {
        for u in 0..nx {
            if is_in(slice[u + nx * v]) {
                n += 1.0;
                sx += u as f64;
                sy += v as f64;
            }
        }
    }
    let mut level = vec![z, 0.0, 0.0];
    level.resize(3 + 2 * angles, 0.0);
    if n == 0.0 {
        return level;
    }
    let (cu, cv) = (sx / n, sy / n);
    level[1] = origin[0] + cu * sp[0];
    level[2] = origin[1] + cv * sp[1];
    let inside = |x: f64, y: f64| {
        let (u, v) = (x.round(), y.round());
        u >= 0.0
            && v >= 0.0
            && (u as usize) < nx
            && (v as usize) < ny
            && is_in(slice[u as usize + nx * v as usize])
    };
    let r_max = ((nx * nx + ny * ny) as f64).sqrt();
    let dr = 0.25;
    for a in 0..angles {
        let th = TAU * a as f64 / angles as f64;
        let (dx, dy) = (th.cos() / sp[0], th.sin() / sp[1]); // mm -> pixels
        // Longest inside run along the ray, in mm.
        let (mut best, mut run_start, mut r) = ((0.0, 0.0), None, 0.0);
        while r <= r_max {
            let hit = inside(cu + dx * r, cv + dy * r);
            match (hit, run_start) {
                (true, None) => run_start = Some(r),
                (false, Some(s)) => {
                    if r - s > best.1 - best.0 {
                        best = (s, r);
                    }
                    run_start = None;
                }
                _ => {}
            }
            r += dr;
        }
        if let Some(s) = run_start
            && r - s > best.1 - best.0
        {
            best = (s, r);
        }
        if best.1 > best.0 {
            level[3 + a] = (best.0 - 0.5).max(0.0);
            level[3 + angles + a] = best.1 - dr + 0.5;
        }
    }
    level
}
