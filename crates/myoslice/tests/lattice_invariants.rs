//! Invariants of the lattice builder on random shapes and on the built-in phantom.

#![allow(clippy::unwrap_used)] // tests fail loudly by design

use myoslice::lattice::check_closed;
use myoslice::prelude::*;
use myoslice::{Label, TissueKind};
use proptest::prelude::*;

fn table() -> LabelTable {
    let l = |id, name: &str, kind| Label {
        id,
        name: name.into(),
        kind,
        origin: None,
        insertion: None,
    };
    LabelTable::new(vec![
        l(0, "background", TissueKind::Background),
        l(1, "fat", TissueKind::Fat),
        l(2, "femur", TissueKind::Bone),
        l(10, "m_a", TissueKind::Muscle),
        l(11, "m_b", TissueKind::Muscle),
        l(12, "m_c", TissueKind::Muscle),
    ])
    .unwrap()
}

/// A random limb-like volume: a skin ellipse, a bone and up to three muscles whose size
/// and position drift with height.
#[derive(Debug, Clone)]
struct Shape {
    skin: (f64, f64),
    bone: (f64, f64, f64),
    muscles: Vec<(f64, f64, f64, f64)>,
    wobble: f64,
}

fn shape() -> impl Strategy<Value = Shape> {
    (
        (16.0..22.0f64, 14.0..20.0f64),
        (-4.0..4.0f64, -4.0..4.0f64, 3.0..7.0f64),
        prop::collection::vec(
            (
                -12.0..12.0f64,
                -12.0..12.0f64,
                3.0..8.0f64,
                0.0..std::f64::consts::TAU,
            ),
            1..=3,
        ),
        0.0..0.4f64,
    )
        .prop_map(|(skin, bone, muscles, wobble)| Shape {
            skin,
            bone,
            muscles,
            wobble,
        })
}

fn rasterise(s: &Shape) -> LabelVolume {
    let (nx, ny, nz) = (56, 52, 36);
    let mut data = vec![0u16; nx * ny * nz];
    for k in 0..nz {
        let t = k as f64 / nz as f64;
        let f = 1.0 + s.wobble * (6.0 * t).sin();
        for j in 0..ny {
            for i in 0..nx {
                let (x, y) = (i as f64 - 28.0, j as f64 - 26.0);
                let mut lab = 0;
                if (x / (s.skin.0 * f)).powi(2) + (y / s.skin.1).powi(2) <= 1.0 {
                    lab = 1;
                    for (m, &(mx, my, r, ph)) in s.muscles.iter().enumerate() {
                        let rr = r * (1.0 + 0.3 * (ph + 4.0 * t).sin());
                        if (x - mx * f).powi(2) + (y - my).powi(2) <= rr * rr {
                            lab = 10 + m as u16;
                        }
                    }
                    if (x - s.bone.0).powi(2) + (y - s.bone.1).powi(2) <= (s.bone.2 * f).powi(2) {
                        lab = 2;
                    }
                }
                data[i + nx * (j + ny * k)] = lab;
            }
        }
    }
    LabelVolume::axis_aligned([nx, ny, nz], [1.0; 3], [0.0; 3], data).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, .. ProptestConfig::default() })]

    #[test]
    fn random_shapes_build_closed_positive_lattices(
        s in shape(),
        rays in 6usize..40,
        step in 1usize..6,
        layers in 1usize..4,
    ) {
        let vol = rasterise(&s);
        let opts = BuildOptions {
            reduction: SliceReduction { slice_step: step, pixel_mm: None },
            rays,
            fat_layers: layers,
            ..BuildOptions::default()
        };
        let lat = Lattice::build(&vol, &table(), &opts).unwrap();
        let inv = lat.check_invariants();
        prop_assert!(inv.is_sound(), "{:?}", inv);
        for b in &lat.bones {
            prop_assert!(check_closed(&b.mesh.triangles).is_ok());
            prop_assert!(b.mesh.volume() > 0.0);
        }
        prop_assert_eq!(lat.fat.hexes.len(), (lat.fat.slices - 1) * rays * layers);
        // Every hexahedron knows its neighbours symmetrically.
        for (h, nb) in lat.fat.neighbours.iter().enumerate() {
            for &n in nb.iter().filter(|&&n| n != u32::MAX) {
                prop_assert!(lat.fat.neighbours[n as usize].contains(&(h as u32)));
            }
        }
    }
}

#[test]
fn phantom_lattice_is_closed_positive_and_keeps_fat_out_of_bone() {
    let (volume, table) = Phantom::default().generate().unwrap();
    let lattice = Lattice::build(&volume, &table, &BuildOptions::default()).unwrap();
    let inv = lattice.check_invariants();
    assert!(inv.is_sound(), "{inv:?}");
    assert!(lattice.muscles.len() >= 16);
    for name in [
        "rectus_femoris",
        "vastus_lateralis",
        "vastus_medialis",
        "vastus_intermedius",
        "biceps_femoris_long",
        "biceps_femoris_short",
        "semitendinosus",
        "semimembranosus",
        "sartorius",
        "gracilis",
        "adductor_magnus",
        "tensor_fasciae_latae",
        "gluteus_maximus",
        "gastrocnemius_medial",
        "gastrocnemius_lateral",
        "soleus",
    ] {
        assert!(lattice.muscle(name).is_some(), "phantom lacks {name}");
    }
    for name in ["hip_bone", "femur", "patella", "tibia", "fibula"] {
        assert!(lattice.bone(name).is_some(), "phantom lacks {name}");
    }
}

#[test]
fn the_phantom_is_deterministic() {
    let a = Phantom {
        voxel_mm: Some(3.0),
    }
    .generate()
    .unwrap();
    let b = Phantom {
        voxel_mm: Some(3.0),
    }
    .generate()
    .unwrap();
    assert_eq!(a.0, b.0);
    let la = Lattice::build(&a.0, &a.1, &BuildOptions::default()).unwrap();
    let lb = Lattice::build(&b.0, &b.1, &BuildOptions::default()).unwrap();
    let bits = |l: &Lattice| -> Vec<u32> {
        l.fat
            .vertices
            .iter()
            .flat_map(|v| v.to_array().map(f32::to_bits))
            .collect()
    };
    assert_eq!(bits(&la), bits(&lb));
}
