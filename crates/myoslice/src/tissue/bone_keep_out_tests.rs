//! Tests of the keep-out from bone and the contact plane ([`super::BoneKeepOut`]).

use super::*;
use crate::body::KneeAxis;
use crate::tissue::knee_fold::KneeFold;

/// A contact plane, and so a knee point, far from the test's rings.
fn far_contact() -> Contact {
    Contact {
        point: Vec3::splat(10.0),
        normal: Vec3::Z,
        behind: Vec3::Y,
        muscle_margin: 0.0,
    }
}

/// A box bone `lo..hi` (m) on the thigh, outward triangles.
fn box_bone(lo: Vec3, hi: Vec3) -> (BodyId, TriMesh) {
    (BodyId::Thigh, crate::tissue::test_shapes::box_mesh(lo, hi))
}

/// The distance fields of `bones`, as a tissue builds them.
fn sdfs_of(bones: &[(BodyId, TriMesh)]) -> Vec<crate::geometry::BoneSdf> {
    bones
        .iter()
        .map(|(_, m)| {
            crate::geometry::BoneSdf::new(
                m.vertices(),
                m.indices(),
                super::super::SDF_CELL_M,
                super::super::SDF_BAND_M,
            )
        })
        .collect()
}

/// `bones` (with their fields `sdfs`) at `frames`, with no contact plane, at 30 Hz.
fn bones_at<'a>(
    sdfs: &'a [crate::geometry::BoneSdf],
    bones: &'a [(BodyId, TriMesh)],
    frames: &'a BodyFrames,
) -> Bones<'a> {
    Bones {
        sdfs,
        surfaces: bones,
        frames,
        fade: fade_per_update(30.0),
        contact: None,
        cover: None,
    }
}

/// Rings of 32 vertices round the z axis, `RINGS` of them 2 mm apart from z = 0, with
/// semi-axes `a` (x) and `b` (y), shifted along z by `dz`.
const RINGS: usize = 5;
fn rings(a: f32, b: f32, dz: f32) -> (Vec<Vec3>, Vec<u32>) {
    let mut p = Vec::new();
    let mut ring_of = Vec::new();
    for r in 0..RINGS {
        for k in 0..32 {
            let t = k as f32 / 32.0 * std::f32::consts::TAU;
            p.push(Vec3::new(a * t.cos(), b * t.sin(), dz + 0.002 * r as f32));
            ring_of.push(r as u32);
        }
    }
    (p, ring_of)
}

/// Runs `updates` updates as a muscle shape does: the rings placed at `base` plus
/// their faded shifts, then pushed out round after round. Returns the largest shift.
fn run(
    keep: &mut BoneKeepOut,
    base: &[Vec3],
    ring_of: &[u32],
    bones: &Bones,
    updates: usize,
) -> f32 {
    for _ in 0..updates {
        keep.fade(bones.fade);
        let mut current: Vec<Vec3> = base
            .iter()
            .zip(ring_of)
            .map(|(p, &r)| *p + keep.shift[r as usize])
            .collect();
        keep.clear_rings(&mut current, ring_of, |_| Vec3::Z, bones);
    }
    keep.shift.iter().map(|s| s.length()).fold(0.0, f32::max)
}

#[test]
fn a_ring_a_bone_reaches_into_from_opposite_sides_is_not_pushed_away() {
    // A bone 20 mm wide from z = 5 mm on, clear of the rings at rest (their inradius,
    // 14.9 mm, is more than its half-diagonal); the rings then move 12 mm along and
    // flatten to a semi-axis of 8 mm in y, so the bone reaches 2 mm into each ring
    // from both sides in y at once (and about as far in x).
    let bones = [box_bone(
        Vec3::new(-0.01, -0.01, 0.005),
        Vec3::new(0.01, 0.01, 0.05),
    )];
    let sdfs = sdfs_of(&bones);
    let frames = BodyFrames::REST;
    let b = bones_at(&sdfs, &bones, &frames);
    let (rest, ring_of) = rings(0.015, 0.015, 0.0);
    let fresh = || BoneKeepOut::new(&rest, RINGS, &bones, &sdfs, &far_contact());
    let mut keep = fresh();
    assert!(!keep.pairs.is_empty(), "no vertex watched");
    let (flat, _) = rings(0.015, 0.008, 0.012);
    let far = run(&mut keep, &flat, &ring_of, &b, 30);
    assert!(far < 1e-4, "a straddling ring moved {:.1} mm", far * 1e3);
    // Reached from one side only (the flat rings 15 mm up in y, their lowest vertices
    // 3 mm into the bone), they are pushed clear on that side.
    let one_sided: Vec<Vec3> = flat
        .iter()
        .map(|p| *p + Vec3::new(0.0, 0.015, 0.0))
        .collect();
    let mut keep = fresh();
    let moved = run(&mut keep, &one_sided, &ring_of, &b, 1);
    assert!(
        moved > 0.003,
        "a ring reached from one side moved {:.1} mm",
        moved * 1e3
    );
    for r in 0..RINGS {
        assert!(keep.shift[r].y > 0.0, "ring {r}: {:?}", keep.shift[r]);
    }
}

/// The knee at the origin, the rest plane level (z up, behind +y), a 1 mm margin.
fn level_plane() -> Contact {
    Contact {
        point: Vec3::ZERO,
        normal: Vec3::Z,
        behind: Vec3::Y,
        muscle_margin: 0.001,
    }
}

/// [`level_plane`] turned 45° into the thigh behind the knee.
fn turned_plane() -> Contact {
    Contact {
        normal: Vec3::new(0.0, -1.0, 1.0).normalize(),
        behind: Vec3::new(0.0, 1.0, 1.0).normalize(),
        ..level_plane()
    }
}

#[test]
fn rings_past_the_contact_plane_go_back_to_their_side_and_rings_across_it_at_rest_stay() {
    // No bone.
    let frames = BodyFrames::REST;
    let rest_plane = level_plane();
    let bones = |contact| Bones {
        sdfs: &[],
        surfaces: &[],
        frames: &frames,
        fade: fade_per_update(30.0),
        contact: Some(contact),
        cover: None,
    };
    // Thigh-side rings (z 10–18 mm) of radius 10 mm round y = 4 mm; the plane turned
    // 45° into the thigh behind the knee reaches 2.8 mm past their back.
    let (rest, ring_of) = rings(0.01, 0.01, 0.01);
    let rest: Vec<Vec3> = rest.iter().map(|p| *p + Vec3::Y * 0.004).collect();
    let turned = turned_plane();
    let past = |keep: &BoneKeepOut| {
        rest.iter()
            .zip(&ring_of)
            .map(|(p, &r)| *p + keep.shift[r as usize])
            .filter(|p| p.dot(turned.behind) > 0.0)
            .map(|p| -p.dot(turned.normal))
            .fold(0.0f32, f32::max)
    };
    let mut keep = BoneKeepOut::new(&rest, RINGS, &[], &[], &rest_plane);
    assert!(
        past(&keep) > 0.0025,
        "the rings start {:.1} mm past",
        past(&keep) * 1e3
    );
    run(&mut keep, &rest, &ring_of, &bones(turned), 20);
    assert!(
        past(&keep) <= 0.0,
        "{:.1} mm past the plane",
        past(&keep) * 1e3
    );
    for s in &keep.shift {
        // Across the rings (their axis is z), toward the thigh's side.
        assert!(s.z == 0.0 && s.y < 0.0, "{s:?}");
    }
    // About 2.8 mm past, and the plane's 1 mm margin, along its normal 45° off the
    // rings' axis: some 5.4 mm across, no more.
    let far = keep.shift[0].length();
    assert!(
        keep.shift[0].y < -0.002 && far < 0.008,
        "{:?}",
        keep.shift[0]
    );
    // Rings across the knee's level (z −4 to 4 mm) and across a rest plane tilted
    // 45°, whose thigh-side vertices lie up to 7 mm past it: each vertex may stay
    // as near the plane, or as far past it, as at rest, so nothing moves.
    let (rest, ring_of) = rings(0.01, 0.01, -0.004);
    let mut keep = BoneKeepOut::new(&rest, RINGS, &[], &[], &turned);
    let moved = run(&mut keep, &rest, &ring_of, &bones(turned), 20);
    assert!(moved == 0.0, "moved {:.1} mm", moved * 1e3);
    // A plane turned only 20° from the rings' axis reaches up to 7.7 mm past the backs
    // of rings round y = 40 mm, but no shift across them clears it without throwing
    // them aside: nothing moves.
    let (rest, ring_of) = rings(0.01, 0.01, 0.01);
    let rest: Vec<Vec3> = rest.iter().map(|p| *p + Vec3::Y * 0.04).collect();
    let (sin, cos) = 20f32.to_radians().sin_cos();
    let steep = Contact {
        normal: Vec3::new(0.0, -sin, cos),
        behind: Vec3::new(0.0, cos, sin),
        ..rest_plane
    };
    assert!(rest.iter().any(|p| p.dot(steep.normal) < -0.007));
    let mut keep = BoneKeepOut::new(&rest, RINGS, &[], &[], &rest_plane);
    let moved = run(&mut keep, &rest, &ring_of, &bones(steep), 20);
    assert!(moved == 0.0, "moved {:.1} mm", moved * 1e3);
}

#[test]
fn rings_under_skin_that_faces_the_plane_keep_beneath_it() {
    // The rings and the plane turned 45° into the thigh of the test above, and thigh
    // skin facing the plane 12 mm from it over their cells: the rings keep that far and
    // the fat's depth (3 mm) more from the plane, not just the plane's 1 mm margin.
    let frames = BodyFrames::REST;
    let (rest_plane, turned) = (level_plane(), turned_plane());
    let along = turned.normal.cross(turned.behind);
    let skin: Vec<(Vec3, Vec3, bool)> = (0..12)
        .flat_map(|i| (-6..6).map(move |j| (i, j)))
        .map(|(i, j)| {
            let p = turned.behind * (0.0025 + 0.005 * i as f32)
                + along * (0.0025 + 0.005 * j as f32)
                + turned.normal * 0.012;
            (p, -turned.normal, true)
        })
        .collect();
    let knee = KneeAxis {
        point: Vec3::ZERO,
        axis: Vec3::X,
        condyle_radius: 0.02,
    };
    let cover = SkinCover::new(
        &skin,
        &KneeFold::new(&knee, 0.0),
        &turned,
        (Quat::IDENTITY, Vec3::ZERO),
        0.003,
    );
    let (rest, ring_of) = rings(0.01, 0.01, 0.01);
    let rest: Vec<Vec3> = rest.iter().map(|p| *p + Vec3::Y * 0.004).collect();
    // How far any vertex behind the axis lies nearer the plane than its floor (m).
    let under = |keep: &BoneKeepOut| {
        rest.iter()
            .zip(&ring_of)
            .map(|(p, &r)| *p + keep.shift[r as usize])
            .filter(|p| p.dot(turned.behind) > 0.0)
            .map(|p| cover.floor(p, true) - p.dot(turned.normal))
            .fold(f32::NEG_INFINITY, f32::max)
    };
    let with = |cover| Bones {
        sdfs: &[],
        surfaces: &[],
        frames: &frames,
        fade: fade_per_update(30.0),
        contact: Some(turned),
        cover,
    };
    let mut plain = BoneKeepOut::new(&rest, RINGS, &[], &[], &rest_plane);
    run(&mut plain, &rest, &ring_of, &with(None), 20);
    assert!(under(&plain) > 0.01, "{:.1} mm", under(&plain) * 1e3);
    let mut keep = BoneKeepOut::new(&rest, RINGS, &[], &[], &rest_plane);
    run(&mut keep, &rest, &ring_of, &with(Some(&cover)), 20);
    assert!(under(&keep) < 1e-4, "{:.1} mm under", under(&keep) * 1e3);
    for s in &keep.shift {
        assert!(s.z == 0.0 && s.y < 0.0, "{s:?}");
    }
}

#[test]
fn carried_rings_find_what_fully_checked_rings_find() {
    // Rings (radius 15 mm, z 0–8 mm) carried by the thigh, 2 mm clear at rest of a thigh
    // bone on +x, and 5 mm clear of a shank bone on −x whose top (z 3 mm) reaches the
    // first ring only. The shank then moves 7 mm along +x, 2 mm into that ring (its way
    // out across the ring shorter than over the top), and pushes it (its neighbours
    // following by shares) into the thigh's bone, which pushes back. Then the shank goes
    // back and the shifts fade, ring by ring, to nothing, the thigh bone's checks of the
    // rings already back skipped. The skips must change nothing.
    let slab =
        |x0: f32, x1: f32, z1: f32| box_bone(Vec3::new(x0, -0.03, -0.01), Vec3::new(x1, 0.03, z1));
    let bones = [
        slab(0.017, 0.045, 0.02),
        (BodyId::Shank, slab(-0.045, -0.02, 0.003).1),
    ];
    let sdfs = sdfs_of(&bones);
    let moved = BodyFrames {
        shank: (Quat::IDENTITY, Vec3::new(0.007, 0.0, 0.0)),
        ..BodyFrames::REST
    };
    let (rest, ring_of) = rings(0.015, 0.015, 0.0);
    let fresh = || BoneKeepOut::new(&rest, RINGS, &bones, &sdfs, &far_contact());
    let (mut carried, mut full) = (fresh(), fresh());
    assert!(
        carried.pairs.iter().any(|&(_, b, _)| b == 0)
            && carried.pairs.iter().any(|&(_, b, _)| b == 1),
        "both bones watched"
    );
    let mut deepest_shift = 0.0f32;
    let mut skipped_pushed = 0;
    for update in 0..160 {
        let frames = if update < 10 { moved } else { BodyFrames::REST };
        let b = bones_at(&sdfs, &bones, &frames);
        for (keep, own) in [(&mut carried, Some(BodyId::Thigh)), (&mut full, None)] {
            keep.fade(b.fade);
            let mut current: Vec<Vec3> = rest
                .iter()
                .zip(&ring_of)
                .map(|(p, &r)| *p + keep.shift[r as usize])
                .collect();
            match own {
                Some(body) => {
                    keep.clear_carried_rings(&mut current, &ring_of, |_| Vec3::Z, &b, body);
                }
                None => {
                    keep.clear_rings(&mut current, &ring_of, |_| Vec3::Z, &b);
                }
            }
        }
        assert_eq!(carried.shift, full.shift, "update {update}");
        deepest_shift = deepest_shift.max(full.shift[0].x);
        if update == 10 {
            skipped_pushed = carried.skipped;
        }
    }
    assert!(
        deepest_shift > 0.002,
        "the shank's bone pushed the first ring {:.1} mm",
        deepest_shift * 1e3
    );
    // Checks were skipped while other rings' shifts were still fading, not only at rest.
    assert!(carried.skipped > skipped_pushed && full.skipped == 0);
    // Faded to nothing, not to a few subnormal units.
    assert!(
        full.shift.iter().all(|s| *s == Vec3::ZERO),
        "{:?}",
        full.shift
    );
}

#[test]
fn a_shift_stays_while_the_bone_needs_it_and_goes_once_the_ring_is_clear_without_it() {
    // A slab bone 10 mm thick beside the rings (x 18–28 mm, clear of their 15 mm radius).
    let bones = [box_bone(
        Vec3::new(0.018, -0.03, -0.01),
        Vec3::new(0.028, 0.03, 0.02),
    )];
    let sdfs = sdfs_of(&bones);
    let frames = BodyFrames::REST;
    let b = bones_at(&sdfs, &bones, &frames);
    let (rest, ring_of) = rings(0.015, 0.015, 0.0);
    let mut keep = BoneKeepOut::new(&rest, RINGS, &bones, &sdfs, &far_contact());
    assert!(!keep.pairs.is_empty(), "no vertex watched");
    // Placed 6 mm toward the bone (3 mm into it), the rings are pushed back and keep
    // that shift update after update while they are placed there.
    let pressed: Vec<Vec3> = rest.iter().map(|p| *p + Vec3::X * 0.006).collect();
    run(&mut keep, &pressed, &ring_of, &b, 20);
    for s in &keep.shift {
        assert!(s.x < -0.002, "{s:?}");
    }
    // Pushed over to the bone's far side (shifted 40 mm along x), rings whose place is
    // clear drop the shift at once, instead of fading through the bone and being pushed
    // back out on its far side every update.
    keep.shift.iter_mut().for_each(|s| *s = Vec3::X * 0.04);
    let left = run(&mut keep, &rest, &ring_of, &b, 1);
    assert_eq!(left, 0.0, "a shift of {:.1} mm stayed", left * 1e3);
}
