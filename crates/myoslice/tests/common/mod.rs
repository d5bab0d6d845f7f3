//! Shared helpers of the integration tests.
#![allow(dead_code)]
#![allow(clippy::unwrap_used)] // tests fail loudly by design

pub mod tool_files;

use std::path::PathBuf;
use std::sync::OnceLock;

use myoslice::muscle::MuscleCatalogue;
use myoslice::prelude::*;

/// A fresh, empty folder of this test process under the system's temporary folder.
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("myoslice-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `../shared/data/visible-human/` relative to the workspace.
pub fn vh_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/visible-human")
}

/// The Visible Human leg, or `None` (with a loud message) when the data are absent and
/// `MYOSLICE_ALLOW_MISSING_DATA=1` says that is expected. Without that variable a missing
/// data folder fails the test: it must never pass silently.
pub fn vh_leg() -> Option<(LabelVolume, LabelTable)> {
    let dir = vh_dir();
    let vol = dir.join("vhf_left_leg_labels.nii.gz");
    let lab = dir.join("vhf_left_leg_labels.json");
    if !vol.exists() || !lab.exists() {
        let msg = format!(
            "Visible Human data not found at {} (expected ../shared beside the workspace)",
            dir.display()
        );
        if std::env::var("MYOSLICE_ALLOW_MISSING_DATA").as_deref() == Ok("1") {
            eprintln!("SKIPPED: {msg}");
            return None;
        }
        panic!("{msg}; set MYOSLICE_ALLOW_MISSING_DATA=1 to skip the tests that need it");
    }
    let v = read_nifti(&vol).expect("the Visible Human volume loads as it is");
    let t = LabelTable::from_path(&lab).expect("the Visible Human label table loads as it is");
    Some((v, t))
}

/// The knee's hamstrings.
pub const HAMSTRINGS: [&str; 4] = [
    "semitendinosus",
    "semimembranosus",
    "biceps_femoris_long",
    "biceps_femoris_short",
];

/// The knee's quadriceps.
pub const QUADRICEPS: [&str; 4] = [
    "rectus_femoris",
    "vastus_lateralis",
    "vastus_medialis",
    "vastus_intermedius",
];

/// Force-weighted moment arm (m) of a muscle group at `deg` of flexion: the group's
/// effective lever.
pub fn group_moment_arm(base: &Simulation, names: &[&str], deg: f64) -> f64 {
    let mut s = base.clone();
    s.set_knee(deg.to_radians(), 0.0).unwrap();
    let (mut num, mut den) = (0.0, 0.0);
    for m in names {
        let u = &s.muscles()[s.muscle_index(m).unwrap()];
        num += u.hill.max_isometric_force * u.moment_arm;
        den += u.hill.max_isometric_force;
    }
    num / den
}

/// Checks the hamstring and quadriceps group moment arms of `base` over 0-120° against
/// the published human ranges (e.g. Buford et al. 1997, Herzog & Read 1993, Spoor & van
/// Leeuwen 1992: hamstrings about 2-4 cm, quadriceps 3-5 cm) and returns the table.
pub fn assert_moment_arms_in_published_ranges(base: &Simulation) -> String {
    let mut report = String::new();
    for deg in [0.0, 30.0, 60.0, 90.0, 120.0] {
        let flex = group_moment_arm(base, &HAMSTRINGS, deg) * 100.0;
        let ext = -group_moment_arm(base, &QUADRICEPS, deg) * 100.0;
        report += &format!("{deg:>5.0}°: hamstrings {flex:.2} cm, quadriceps {ext:.2} cm\n");
        assert!(
            (2.0..=4.5).contains(&flex),
            "hamstrings moment arm {flex:.2} cm at {deg}°\n{report}"
        );
        assert!(
            (3.0..=5.0).contains(&ext),
            "quadriceps moment arm {ext:.2} cm at {deg}°\n{report}"
        );
    }
    report
}

/// The Visible Human leg's lattice (None without the data), built once per test binary.
pub fn vh_lattice() -> Option<&'static Lattice> {
    static L: OnceLock<Option<Lattice>> = OnceLock::new();
    L.get_or_init(|| {
        vh_leg().map(|(v, t)| Lattice::build(&v, &t, &BuildOptions::default()).unwrap())
    })
    .as_ref()
}

/// The phantom's lattice, built once per test binary.
pub fn phantom_lattice() -> &'static Lattice {
    static L: OnceLock<Lattice> = OnceLock::new();
    L.get_or_init(|| {
        let (v, t) = Phantom::default().generate().unwrap();
        Lattice::build(&v, &t, &BuildOptions::default()).unwrap()
    })
}

/// Muscles with surface vertices more than 1 mm inside a bone of `lattice` and no more
/// than 3 cm from its surface: name, how many, the deepest (m). Exact where a bone's tubes
/// overlap too: a bone of one tube is asked by pseudo-normals confirmed by the winding
/// number, a bone of several by the winding number alone.
pub fn muscles_in_bone_at_build(lattice: &Lattice) -> Vec<(String, usize, f32)> {
    use myoslice::lattice::{oriented_trimesh, winding_number};
    use parry3d::query::PointQuery;
    let bones: Vec<_> = lattice
        .bones
        .iter()
        .map(|b| {
            (
                oriented_trimesh(&b.mesh.vertices, &b.mesh.triangles).unwrap(),
                b,
            )
        })
        .collect();
    let mut out = Vec::new();
    for m in &lattice.muscles {
        let (mut n, mut deepest) = (0, 0.0f32);
        for r in &m.mesh.rings {
            for v in r.first..r.centre {
                let p = m.mesh.vertices[v as usize];
                for (t, b) in &bones {
                    if !t.local_aabb().contains_local_point(p) {
                        continue;
                    }
                    let Some(proj) = t.project_local_point_with_max_dist(p, false, 0.03) else {
                        continue;
                    };
                    let winding = || winding_number(&b.mesh.vertices, &b.mesh.triangles, p);
                    let inside = if b.mesh.tubes.len() == 1 {
                        proj.is_inside && winding().abs() > 0.5
                    } else {
                        winding().abs() > 0.5
                    };
                    if inside {
                        let d = proj.point.distance(p);
                        n += usize::from(d > 1e-3);
                        deepest = deepest.max(d);
                    }
                }
            }
        }
        if n > 0 {
            out.push((m.name.clone(), n, deepest));
        }
    }
    out
}

/// Drives a flexion to deep flexion with the hamstrings, then back with the quadriceps,
/// and calls `check` on every tissue update.
pub fn flex_and_back(sim: &mut Simulation, speed: f64, mut check: impl FnMut(&Simulation)) -> f64 {
    let flex = [
        "semitendinosus",
        "semimembranosus",
        "biceps_femoris_long",
        "biceps_femoris_short",
        "gracilis",
        "sartorius",
    ];
    let ext = [
        "rectus_femoris",
        "vastus_lateralis",
        "vastus_medialis",
        "vastus_intermedius",
    ];
    let mut max_angle = 0.0f64;
    let period = sim.tissue().unwrap().period();
    let steps = (1.6 / speed / period).ceil() as usize;
    for k in 0..steps {
        let t = k as f64 * period * speed;
        for m in flex {
            sim.set_excitation(m, if t < 0.8 { 1.0 } else { 0.0 })
                .unwrap();
        }
        for m in ext {
            sim.set_excitation(m, if t < 0.8 { 0.0 } else { (0.6 * speed).min(1.0) })
                .unwrap();
        }
        sim.step(period).unwrap();
        max_angle = max_angle.max(sim.knee_angle());
        check(sim);
    }
    max_angle
}

/// The phantom's simulation with the default options.
pub fn phantom() -> Simulation {
    Simulation::new(
        phantom_lattice().clone(),
        SimulationConfig::default(),
        &MuscleCatalogue::default(),
    )
    .unwrap()
}

/// The Visible Human leg's simulation with the default options (None without the data).
pub fn visible_human() -> Option<Simulation> {
    let lattice = vh_lattice()?;
    Some(
        Simulation::new(
            lattice.clone(),
            SimulationConfig::default(),
            &MuscleCatalogue::default(),
        )
        .unwrap(),
    )
}

/// How broken the tissue is after the last tissue update.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Breaks {
    /// Fat elements with a folded corner (VTK's test of a valid hexahedron).
    pub folded: usize,
    /// Fat elements of zero or negative volume.
    pub inverted: usize,
    /// Crossing pairs among the skin's triangles.
    pub crossings: usize,
    /// Whether every fat vertex is finite.
    pub finite: bool,
}

/// After the last tissue update: folded and inverted fat elements, crossing pairs among
/// the skin's `triangles` (`sim.lattice().fat.surface_triangles()`), and whether every
/// fat vertex is finite.
pub fn tissue_breaks(sim: &Simulation, triangles: &[[u32; 3]]) -> Breaks {
    let t = sim.tissue().unwrap();
    let x = t.fat_vertices();
    let m = sim.tissue_metrics().unwrap();
    Breaks {
        folded: m.inverted,
        inverted: m.negative_volume,
        crossings: myoslice::tissue::intersect::self_intersections(x, triangles),
        finite: x.iter().all(|p| p.is_finite()),
    }
}

/// Muscle vertices more than 1 mm out through the skin now, and the farthest (m).
pub fn muscles_out(sim: &Simulation) -> (usize, f32) {
    let out = sim.muscles_outside_skin().unwrap();
    (
        out.iter().map(|b| b.vertices_over_1mm).sum(),
        out.iter().map(|b| b.farthest_m).fold(0.0, f32::max),
    )
}

/// Muscle vertices more than 1 mm inside bone now beyond the `rest` count (the slices
/// let muscle and bone overlap at rest), and the deepest of the muscles that reach
/// deeper than at `rest` (m; 0 when none does).
pub fn muscles_in_bone_beyond(
    sim: &Simulation,
    rest: &[myoslice::tissue::BoneOverlap],
) -> (usize, f32) {
    let now = sim.muscles_in_bone().unwrap();
    let count: usize = now.iter().map(|o| o.vertices_over_1mm).sum();
    let at_rest: usize = rest.iter().map(|o| o.vertices_over_1mm).sum();
    let deepest = now
        .iter()
        .zip(rest)
        .filter(|(n, r)| n.deepest_m > r.deepest_m)
        .map(|(n, _)| n.deepest_m)
        .fold(0.0, f32::max);
    (count.saturating_sub(at_rest), deepest)
}

/// A fresh tissue of a simulation (its own copy, to move by hand).
pub fn tissue_of(sim: &Simulation) -> myoslice::tissue::Tissue {
    tissue_with(sim, Default::default())
}

/// [`tissue_of`] with the options `config`.
pub fn tissue_with(
    sim: &Simulation,
    config: myoslice::tissue::TissueConfig,
) -> myoslice::tissue::Tissue {
    let lat = sim.lattice();
    let meshes: Vec<_> = (0..lat.bones.len())
        .map(|i| sim.skeleton().bone_trimesh(i).unwrap())
        .collect();
    myoslice::tissue::Tissue::new(
        lat,
        sim.muscles(),
        *sim.skeleton().knee(),
        myoslice::tissue::bone_surfaces(lat, &meshes),
        config,
    )
    .unwrap()
}
