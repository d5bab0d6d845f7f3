//! One muscle-tendon unit: its chain, its Hill parameters and its state.

use glam::Vec3;
use parry3d::query::PointQuery;
use parry3d::shape::TriMesh;

use super::catalogue::{MuscleCatalogue, MuscleGroup};
use super::chain::{Attachment, BodyFrames, ConeAnchor, MuscleChain};
use super::hill::{FibreState, HillParams};
use super::tendon::TendonModel;
use super::wrap::WrapCylinder;
use crate::body::{BodyId, KneeAxis, body_of_bone};
use crate::error::{Error, Result};
use crate::lattice::{Lattice, MuscleLattice};

/// Chain points of knee-crossing muscles keep this distance (m) from the knee axis.
const KNEE_CLEARANCE: f32 = 0.10;

/// Interior points of a knee-crossing belly that starts at the knee keep this distance
/// (m) from the axis.
const ORIGIN_CLEARANCE: f32 = 0.06;

/// Muscle tissue density (kg/m³).
pub const MUSCLE_DENSITY: f64 = 1060.0;

/// Options for building chains.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChainOptions {
    /// Target spacing of chain points along the belly (m).
    pub spacing: f64,
    /// Cone half-angle (rad).
    pub cone_half_angle: f64,
    /// Chain stiffness relative to the muscle's maximum force.
    pub stiffness: f32,
    /// Gravity (m/s²).
    pub gravity: Vec3,
}

/// A muscle-tendon unit of the simulation.
#[derive(Debug)]
pub struct MuscleUnit {
    /// Name (label table).
    pub name: String,
    /// Index of its lattice in [`Lattice::muscles`].
    pub lattice_index: usize,
    /// Control group.
    pub group: MuscleGroup,
    /// Hill parameters, lengths scaled to this model.
    pub hill: HillParams,
    /// The Hill parameters as built, before any [`crate::muscle::MuscleScale`].
    pub built_hill: HillParams,
    /// The chain.
    pub chain: MuscleChain,
    /// Whether origin and insertion are on different bodies (it moves the knee).
    pub crosses_knee: bool,
    /// Mass (kg) from the lattice volume.
    pub mass: f64,
    /// Origin and insertion bone names.
    pub bones: (String, String),
    /// Whether the catalogue knew it (else the default rule made its parameters).
    pub from_catalogue: bool,
    /// Excitation in [0, 1].
    pub excitation: f64,
    /// Activation in [0, 1].
    pub activation: f64,
    /// Path length (m).
    pub path_length: f64,
    /// Path lengthening velocity (m/s).
    pub path_velocity: f64,
    /// Tendon force of the last step (N).
    pub force: f64,
    /// Fibre state of the last step.
    pub fibre: FibreState,
    /// Its tendon model (Hill mode): the catalogue's for this muscle, else the
    /// simulation's default.
    pub tendon: TendonModel,
    /// Moment arm about the knee (m), positive for flexion, of the last step (the one its
    /// force and the knee torque went with).
    pub moment_arm: f64,
    /// Moment arm at the chain's current geometry (m): the next step's.
    pub current_moment_arm: f64,
}

impl Clone for MuscleUnit {
    fn clone(&self) -> Self {
        Self {
            name: self.name.clone(),
            lattice_index: self.lattice_index,
            group: self.group,
            hill: self.hill,
            built_hill: self.built_hill,
            chain: self.chain.clone(),
            crosses_knee: self.crosses_knee,
            mass: self.mass,
            bones: self.bones.clone(),
            from_catalogue: self.from_catalogue,
            excitation: self.excitation,
            activation: self.activation,
            path_length: self.path_length,
            path_velocity: self.path_velocity,
            force: self.force,
            fibre: self.fibre,
            tendon: self.tendon,
            moment_arm: self.moment_arm,
            current_moment_arm: self.current_moment_arm,
        }
    }

    /// Copies into the buffers already here (see [`MuscleChain`]'s `clone_from`).
    fn clone_from(&mut self, o: &Self) {
        // Every field named, so that a new one cannot be forgotten here.
        let Self {
            name,
            lattice_index,
            group,
            hill,
            built_hill,
            chain,
            crosses_knee,
            mass,
            bones,
            from_catalogue,
            excitation,
            activation,
            path_length,
            path_velocity,
            force,
            fibre,
            tendon,
            moment_arm,
            current_moment_arm,
        } = o;
        self.name.clone_from(name);
        self.bones.clone_from(bones);
        self.chain.clone_from(chain);
        (self.lattice_index, self.group) = (*lattice_index, *group);
        (self.hill, self.built_hill) = (*hill, *built_hill);
        (self.crosses_knee, self.mass, self.from_catalogue) =
            (*crosses_knee, *mass, *from_catalogue);
        (self.excitation, self.activation, self.force) = (*excitation, *activation, *force);
        (self.path_length, self.path_velocity, self.fibre) = (*path_length, *path_velocity, *fibre);
        (self.moment_arm, self.current_moment_arm) = (*moment_arm, *current_moment_arm);
        self.tendon = *tendon;
    }
}

fn bone_index(lattice: &Lattice, name: &str) -> Option<usize> {
    lattice.bones.iter().position(|b| b.name == name)
}

fn bone_centroid(lattice: &Lattice, i: usize) -> Vec3 {
    let v = &lattice.bones[i].mesh.vertices;
    v.iter().copied().sum::<Vec3>() / v.len().max(1) as f32
}

/// Nearest bone (index) to `p` among `meshes`, with the projection and triangle.
fn nearest_bone(meshes: &[&TriMesh], p: Vec3) -> Option<(usize, Vec3, u32)> {
    meshes
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let (proj, _) = m.project_local_point_and_get_feature(p);
            (i, proj.point, proj.subshape)
        })
        .min_by(|a, b| a.1.distance_squared(p).total_cmp(&b.1.distance_squared(p)))
}

impl MuscleUnit {
    /// Builds the unit of lattice muscle `index`. `meshes` are the bone surfaces (lattice
    /// bone order, rest coordinates); `default_tendon` is its tendon model unless the catalogue
    /// gives it one.
    pub fn build(
        lattice: &Lattice,
        index: usize,
        meshes: &[&TriMesh],
        knee: &KneeAxis,
        catalogue: &MuscleCatalogue,
        opts: &ChainOptions,
        default_tendon: TendonModel,
    ) -> Result<Self> {
        let m: &MuscleLattice = &lattice.muscles[index];
        let entry = catalogue.muscles.get(&m.name);
        let caps: Vec<_> = m.mesh.rings.iter().filter(|r| r.cap).collect();
        let (lo, hi) = match (
            caps.iter().min_by_key(|r| r.k),
            caps.iter().max_by_key(|r| r.k),
        ) {
            (Some(a), Some(b)) => (
                m.mesh.vertices[a.centre as usize],
                m.mesh.vertices[b.centre as usize],
            ),
            _ => return Err(Error::Build(format!("muscle '{}' has no lattice", m.name))),
        };
        // Bones: catalogue override, else label table, else the nearest bone to each end.
        let named = |n: Option<&String>| n.and_then(|n| bone_index(lattice, n));
        let origin_name = entry.and_then(|e| e.origin.as_ref()).or(m.origin.as_ref());
        let insertion_name = entry
            .and_then(|e| e.insertion.as_ref())
            .or(m.insertion.as_ref());
        let near = |p: Vec3| nearest_bone(meshes, p).map(|b| b.0);
        let ob = named(origin_name).or_else(|| near(hi));
        let ib = named(insertion_name).or_else(|| near(lo));
        let (Some(ob), Some(ib)) = (ob, ib) else {
            return Err(Error::Build(format!(
                "muscle '{}': no bone to attach to",
                m.name
            )));
        };
        // The origin end is the one nearer the origin bone's side (superior when the
        // origin bone lies higher, or when both ends share a bone).
        let origin_superior =
            ob == ib || bone_centroid(lattice, ob).z >= bone_centroid(lattice, ib).z;
        let (o_end, i_end) = if origin_superior { (hi, lo) } else { (lo, hi) };
        let mut belly: Vec<Vec3> = Vec::with_capacity(m.centre_line.len() + 2);
        belly.push(o_end);
        if origin_superior {
            belly.extend(m.centre_line.iter().rev());
        } else {
            belly.extend(m.centre_line.iter());
        }
        belly.push(i_end);
        let project = |bone: usize, p: Vec3| meshes[bone].project_local_point(p, false).point;
        let site = |bone: usize, end: Vec3, which: Option<&String>| match which.map(String::as_str)
        {
            Some("superior") => extreme(meshes[bone], Vec3::Z),
            Some("inferior") => extreme(meshes[bone], Vec3::NEG_Z),
            _ => project(bone, end),
        };
        // The vertex of `bone` nearest `end` among those on the far side of a level `d`
        // above (+) or below (−) the knee axis.
        let beyond = |bone: usize, end: Vec3, d: f32| {
            meshes[bone]
                .vertices()
                .iter()
                .copied()
                .filter(|v| (v.z - knee.point.z) * d.signum() >= d.abs())
                .min_by(|a, b| a.distance_squared(end).total_cmp(&b.distance_squared(end)))
                .unwrap_or_else(|| project(bone, end))
        };
        let o_att = match entry.and_then(|e| e.origin_above_knee_m) {
            Some(d) => beyond(ob, o_end, d as f32),
            None => site(ob, o_end, entry.and_then(|e| e.origin_site.as_ref())),
        };
        let i_site = entry.and_then(|e| e.insertion_site.as_ref());
        let below = entry.and_then(|e| e.insertion_below_knee_m);
        let i_att = if i_site.is_some_and(|s| s == "anteromedial") {
            let d = below.unwrap_or(0.0) as f32;
            anteromedial(lattice, ib, knee, d).unwrap_or_else(|| project(ib, i_end))
        } else {
            match below {
                Some(d) => beyond(ib, i_end, -d as f32),
                None => site(ib, i_end, i_site),
            }
        };
        let belly_len: f64 = belly
            .windows(2)
            .map(|w| f64::from(w[0].distance(w[1])))
            .sum();
        let n_belly = ((belly_len / opts.spacing).round() as usize + 1).clamp(3, 12);
        let mut pts = resample(&belly, n_belly);
        // A tendon shorter than a third of the spacing is dropped: the belly starts (ends)
        // at the bone. Very short segments would only make the chain stiff.
        let min_seg = (opts.spacing / 3.0) as f32;
        let drop_first = o_att.distance(pts[0]) < min_seg;
        let drop_last = i_att.distance(pts[pts.len() - 1]) < min_seg;
        if drop_first {
            pts.remove(0);
        }
        if drop_last {
            pts.pop();
        }
        // For a muscle crossing the knee, chain points within a few centimetres of the
        // axis would act as pulleys fixed to the femur that the insertion could swing
        // past at deep flexion; the tendon runs from the last point clear of the knee.
        let crossing =
            body_of_bone(&lattice.bones[ob].name) != body_of_bone(&lattice.bones[ib].name);
        let mut belly_from_origin = drop_first;
        if crossing {
            let dist = |p: Vec3| {
                let d = p - knee.point;
                (d - knee.axis * d.dot(knee.axis)).length()
            };
            while pts.len() > 1
                && dist(pts[pts.len() - 1]) < KNEE_CLEARANCE
                && pts[pts.len() - 1].z > knee.point.z - KNEE_CLEARANCE
            {
                pts.pop();
            }
            // Likewise where the belly starts at the knee (the gastrocnemii arise on the
            // condyles): its first points would be pulleys on whichever bone lies
            // nearest, turning the line of action through the axis as the knee bends.
            while pts.len() > 1 && dist(pts[0]) < ORIGIN_CLEARANCE {
                pts.remove(0);
                belly_from_origin = true;
            }
        }
        let mut x = Vec::with_capacity(pts.len() + 3);
        x.push(o_att);
        x.extend(pts);
        let via = entry
            .and_then(|e| e.via_above_insertion_m)
            .map(|d| i_att + Vec3::Z * d as f32);
        if let Some(v) = via {
            x.push(v);
        }
        x.push(i_att);
        let nseg = x.len() - 1;
        let n_via = usize::from(via.is_some());
        let tendon: Vec<bool> = (0..nseg)
            .map(|i| {
                (i == 0 && !belly_from_origin)
                    || (i + 1 + n_via >= nseg && !(drop_last && n_via == 0))
            })
            .collect();
        let n = x.len();
        let volume = m.mesh.volume().abs();
        let mass = volume * MUSCLE_DENSITY;
        let interior = (n - 2).max(1);
        let mut masses = vec![0.0f32; n];
        for mm in masses.iter_mut().take(n - 1 - n_via).skip(1) {
            *mm = (mass / (interior - n_via).max(1) as f64) as f32;
        }
        let cones = (0..n)
            .map(|i| {
                if i == 0 || i + 1 + n_via >= n {
                    return None;
                }
                let (bone, _, tri) = nearest_bone(meshes, x[i])?;
                let t = meshes[bone].triangle(tri % meshes[bone].num_triangles() as u32);
                let apex = (t.a + t.b + t.c) / 3.0;
                let axis = (x[i] - apex)
                    .try_normalize()
                    .unwrap_or_else(|| (t.b - t.a).cross(t.c - t.a).normalize_or(Vec3::Z));
                Some(ConeAnchor::new(
                    body_of_bone(&lattice.bones[bone].name),
                    apex,
                    axis,
                    x[i],
                ))
            })
            .collect();
        let o_body_early = body_of_bone(&lattice.bones[ob].name);
        let rest_len: Vec<f32> = x
            .windows(2)
            .map(|w| w[0].distance(w[1]).max(1e-4))
            .collect();
        let belly_rest = rest_len
            .iter()
            .zip(&tendon)
            .filter(|(_, t)| !**t)
            .map(|(l, _)| *l)
            .sum();
        let o_body = body_of_bone(&lattice.bones[ob].name);
        let i_body = body_of_bone(&lattice.bones[ib].name);
        let crosses_knee = o_body != i_body;
        let ha = opts.cone_half_angle as f32;
        let mut chain = MuscleChain {
            origin: Attachment {
                body: o_body,
                rest: o_att,
            },
            insertion: Attachment {
                body: i_body,
                rest: i_att,
            },
            v: vec![Vec3::ZERO; n],
            x,
            mass: masses,
            rest_len,
            tendon,
            cones,
            vias: via
                .map(|v| {
                    vec![(
                        n - 2,
                        Attachment {
                            body: o_body_early,
                            rest: v,
                        },
                    )]
                })
                .unwrap_or_default(),
            cone_cos_tan: (ha.cos(), ha.tan()),
            wrap: None,
            wrap_segment: n - 2,
            wrapped: false,
            belly_rest,
            scratch: Default::default(),
            geom: Vec::new(),
            bodies: Vec::new(),
        };
        chain.index_bodies();
        let explicit_wrap = entry.and_then(|e| e.wrap_radius_m).is_some();
        if crosses_knee && (explicit_wrap || wrap_fits(&chain, knee)) {
            // The segment crossing the knee: from the last point moving with the origin's
            // body to the next one.
            let k = (0..n - 1)
                .find(|&i| chain.point_body(i) == o_body && chain.point_body(i + 1) != o_body)
                .unwrap_or(n - 2);
            chain.wrap_segment = k;
            let (p, q) = (chain.x[k], chain.x[k + 1]);
            // A flexor's tendon never crosses the front of the knee nor an extensor's its
            // back, even where the straight line at rest would (the pes anserinus lies in
            // front of the axis; its tendons come round the medial condyle from behind).
            let side = match entry.and_then(|e| e.group) {
                Some(MuscleGroup::Flexor) => {
                    WrapCylinder::side_avoiding(knee.point, knee.axis, p, q, Vec3::Y)
                }
                Some(MuscleGroup::Extensor) => {
                    WrapCylinder::side_avoiding(knee.point, knee.axis, p, q, Vec3::NEG_Y)
                }
                _ => WrapCylinder::side_of(knee.point, knee.axis, p, q),
            };
            let probe = WrapCylinder {
                point: knee.point,
                axis: knee.axis,
                radius: 0.0,
                side,
            };
            let clearance = probe.clearance(p, q).abs();
            let dist = |p: Vec3| {
                let d = p - knee.point;
                (d - knee.axis * d.dot(knee.axis)).length()
            };
            // The cylinder must leave both ends of the segment outside it.
            let room = 0.9 * dist(p).min(dist(q));
            let radius = entry
                .and_then(|e| e.wrap_radius_m)
                .map_or((0.9 * clearance).clamp(0.01, 0.06), |r| r as f32)
                .min(room);
            chain.wrap = Some(WrapCylinder { radius, ..probe });
            // A straight line on the wrong side at rest starts wrapped (a wrapped path
            // stays so until it clears the cylinder on its side).
            chain.wrapped = probe.clearance(p, q) < 0.0;
            chain.update_wrap();
        }
        chain.attach_ends(&BodyFrames::REST);
        chain.refresh();
        let r0 = catalogue.resolve(&m.name, volume, chain.path_length());
        let fmax = r0.max_isometric_force as f32;
        chain.settle(
            &BodyFrames::REST,
            0.3 * fmax,
            opts.stiffness * fmax,
            opts.gravity,
        );
        let path = chain.path_length();
        let r = catalogue.resolve(&m.name, volume, path);
        // One factor scales fibre and tendon so that at rest, on this model's own path,
        // the fibre has its catalogued rest length (rigid tendon, constant thickness).
        let lr = r.rest_fibre_length;
        let along = (lr * lr - r.pennation.sin().powi(2)).max(1e-6).sqrt();
        let s = path / (r.tendon_slack_length + r.optimal_fibre_length * along);
        let hill = HillParams::new(
            r.max_isometric_force,
            r.optimal_fibre_length * s,
            r.tendon_slack_length * s,
            r.pennation,
            r.max_contraction_velocity,
        );
        let fibre = hill.rigid_tendon_kinematics(path, 0.0);
        Ok(Self {
            name: m.name.clone(),
            lattice_index: index,
            group: r.group,
            hill,
            built_hill: hill,
            chain,
            crosses_knee,
            mass,
            bones: (
                lattice.bones[ob].name.clone(),
                lattice.bones[ib].name.clone(),
            ),
            from_catalogue: r.from_catalogue,
            excitation: 0.0,
            activation: 0.0,
            path_length: path,
            path_velocity: 0.0,
            force: 0.0,
            fibre,
            tendon: entry.and_then(|e| e.tendon).unwrap_or(default_tendon),
            moment_arm: 0.0,
            current_moment_arm: 0.0,
        })
    }

    /// Whether the chain's insertion is on the shank and its origin on the thigh, or the
    /// other way round.
    pub fn insertion_body(&self) -> BodyId {
        self.chain.insertion.body
    }
}

/// Whether a knee-crossing tendon runs far enough from the axis to wrap: its thigh-side
/// point must be clear of the condyles (the gastrocnemii and popliteus start on them and
/// cross the knee in a short straight line).
fn wrap_fits(chain: &MuscleChain, knee: &KneeAxis) -> bool {
    let n = chain.len();
    let o_body = chain.origin.body;
    let k = (0..n - 1)
        .find(|&i| chain.point_body(i) == o_body && chain.point_body(i + 1) != o_body)
        .unwrap_or(n - 2);
    let d = chain.x[k] - knee.point;
    (d - knee.axis * d.dot(knee.axis)).length() >= 2.5 * WRAP_MIN_RADIUS
}

/// The most anteromedial vertex of bone `bone` in a band just below `below` m under the
/// knee axis: the pes anserinus, where the semitendinosus, gracilis and sartorius insert
/// on the tibia's anteromedial face after wrapping round its medial condyle. Medial is
/// the side away from the fibula; without a fibula, anterior alone.
fn anteromedial(lattice: &Lattice, bone: usize, knee: &KneeAxis, below: f32) -> Option<Vec3> {
    const BAND: f32 = 0.015;
    let medial = bone_index(lattice, "fibula").map_or(Vec3::ZERO, |f| {
        Vec3::X * (bone_centroid(lattice, bone).x - bone_centroid(lattice, f).x).signum()
    });
    let dir = (Vec3::Y + medial).normalize();
    let top = knee.point.z - below;
    lattice.bones[bone]
        .mesh
        .vertices
        .iter()
        .copied()
        .filter(|v| v.z <= top && v.z >= top - BAND)
        .max_by(|a, b| a.dot(dir).total_cmp(&b.dot(dir)))
}

/// Smallest wrap cylinder considered (m).
const WRAP_MIN_RADIUS: f32 = 0.02;

/// The vertex of a mesh furthest along `dir`.
fn extreme(mesh: &TriMesh, dir: Vec3) -> Vec3 {
    mesh.vertices()
        .iter()
        .copied()
        .max_by(|a, b| a.dot(dir).total_cmp(&b.dot(dir)))
        .unwrap_or(Vec3::ZERO)
}

/// `n` points at equal arc length along a polyline.
fn resample(p: &[Vec3], n: usize) -> Vec<Vec3> {
    let mut cum = vec![0.0f32];
    for w in p.windows(2) {
        cum.push(cum[cum.len() - 1] + w[0].distance(w[1]));
    }
    let total = cum[cum.len() - 1];
    let mut out = Vec::with_capacity(n);
    let mut j = 0;
    for k in 0..n {
        let s = total * k as f32 / (n - 1) as f32;
        while j + 2 < cum.len() && cum[j + 1] < s {
            j += 1;
        }
        let len = cum[j + 1] - cum[j];
        let t = if len > 0.0 {
            ((s - cum[j]) / len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        out.push(p[j].lerp(p[j + 1], t));
    }
    out
}
