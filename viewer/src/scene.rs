//! CPU-side meshes of the simulation, ready to upload: bones, muscles and the body surface
//! coloured by its per-element metrics.

use std::ops::Range;

use glam::Vec3;
use myoslice::Simulation;
use myoslice::body::BodyId;

use crate::colormap::{self, ColorMode};

/// One vertex as the shader reads it.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Vertex {
    /// Position (world, m).
    pub pos: [f32; 3],
    /// Unit normal.
    pub normal: [f32; 3],
    /// Linear RGBA.
    pub color: [f32; 4],
}

/// Drawn layers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layer {
    /// Bones.
    Bone = 0,
    /// Muscles.
    Muscle = 1,
    /// The body surface (skin over the fat).
    Skin = 2,
}

/// What to draw and how.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneOptions {
    /// Colour of the body surface.
    pub color_mode: ColorMode,
    /// Visibility of bone, muscle, skin.
    pub visible: [bool; 3],
    /// Opacity of bone, muscle, skin.
    pub opacity: [f32; 3],
    /// Muscle highlighted (index in the simulation's muscle order).
    pub selected_muscle: Option<usize>,
    /// Muscle under the cursor, tinted lighter.
    pub hovered_muscle: Option<usize>,
    /// Half-width of the area-change scale in log2(A/A0) (None: 1, i.e. ×2 and ×½).
    pub area_range: Option<f32>,
    /// Fixed scale for deformation degree, m (None: from the data).
    pub degree_range: Option<f32>,
}

impl Default for SceneOptions {
    fn default() -> Self {
        Self {
            color_mode: ColorMode::Area,
            visible: [true, true, true],
            opacity: [1.0, 1.0, 0.45],
            selected_muscle: None,
            hovered_muscle: None,
            area_range: None,
            degree_range: None,
        }
    }
}

/// Meshes of one frame.
#[derive(Debug, Clone, Default)]
pub struct SceneMesh {
    /// All vertices.
    pub vertices: Vec<Vertex>,
    /// Triangle indices.
    pub indices: Vec<u32>,
    /// Index range of each layer (bone, muscle, skin).
    pub ranges: [Range<u32>; 3],
    /// Index range of each drawn muscle, with its index in the simulation's order,
    /// ascending (for picking).
    pub muscle_ranges: Vec<(usize, Range<u32>)>,
    /// Bounding box of everything.
    pub bounds: (Vec3, Vec3),
    /// Scale used for the surface colours (log2 area ratio, or degree in m).
    pub color_range: f32,
}

/// Area-weighted vertex normals of a triangle set.
pub fn vertex_normals(v: &[Vec3], tris: &[[u32; 3]]) -> Vec<Vec3> {
    let mut n = vec![Vec3::ZERO; v.len()];
    for t in tris {
        let [a, b, c] = t.map(|i| v[i as usize]);
        let f = (b - a).cross(c - a);
        for &i in t {
            n[i as usize] += f;
        }
    }
    n.iter().map(|x| x.normalize_or(Vec3::Z)).collect()
}

impl SceneMesh {
    fn push_mesh(&mut self, v: &[Vec3], tris: &[[u32; 3]], color: [f32; 4]) {
        let base = self.vertices.len() as u32;
        let normals = vertex_normals(v, tris);
        self.vertices
            .extend(v.iter().zip(&normals).map(|(p, n)| Vertex {
                pos: p.to_array(),
                normal: n.to_array(),
                color,
            }));
        self.indices
            .extend(tris.iter().flat_map(|t| t.map(|i| base + i)));
    }

    /// Builds the frame of a simulation.
    pub fn build(sim: &Simulation, opts: &SceneOptions) -> Self {
        let mut s = SceneMesh::default();
        let lat = sim.lattice();
        let frames = sim.frames();
        // Bones, moved with their bodies (also framed when hidden).
        let bones: Vec<Vec<Vec3>> = (0..lat.bones.len()).map(|i| sim.bone_vertices(i)).collect();
        let start = s.indices.len() as u32;
        if opts.visible[0] {
            let c = colormap::BONE;
            for (b, v) in lat.bones.iter().zip(&bones) {
                s.push_mesh(v, &b.mesh.triangles, [c[0], c[1], c[2], opts.opacity[0]]);
            }
        }
        s.ranges[0] = start..s.indices.len() as u32;
        // The tissue's last update carried with the bones to now: it updates at its own
        // rate, the bones every step.
        let carried = sim.carried_tissue();
        // Muscles: their deformed shapes when the tissue runs.
        let start = s.indices.len() as u32;
        if opts.visible[1] {
            for (i, m) in sim.muscles().iter().enumerate() {
                let lm = &lat.muscles[m.lattice_index];
                let c = if opts.selected_muscle == Some(i) {
                    colormap::SELECTED
                } else if opts.hovered_muscle == Some(i) {
                    colormap::HOVERED
                } else {
                    colormap::MUSCLE
                };
                let color = [c[0], c[1], c[2], opts.opacity[1]];
                let from = s.indices.len() as u32;
                match &carried {
                    Some(c) => s.push_mesh(&c.muscles[i], &lm.mesh.triangles, color),
                    None => s.push_mesh(&sim.muscle_vertices(i), &lm.mesh.triangles, color),
                }
                s.muscle_ranges.push((i, from..s.indices.len() as u32));
            }
        }
        s.ranges[1] = start..s.indices.len() as u32;
        // Skin: the outer faces of the fat, one flat colour per element.
        let start = s.indices.len() as u32;
        let fat_x: Vec<Vec3> = match carried {
            Some(c) => c.fat,
            None => lat
                .fat
                .vertices
                .iter()
                .map(|p| {
                    let body = if p.z < sim.skeleton().knee().point.z {
                        BodyId::Shank
                    } else {
                        BodyId::Thigh
                    };
                    frames.point(body, *p)
                })
                .collect(),
        };
        let faces = lat.fat.outer_faces();
        let metrics = sim.tissue_metrics();
        let (values, range): (Vec<f32>, f32) = match (opts.color_mode, metrics) {
            (ColorMode::Area, Some(m)) => {
                let v: Vec<f32> = faces
                    .iter()
                    .map(|(h, _)| m.area_change[*h as usize])
                    .collect();
                (v, opts.area_range.unwrap_or(1.0))
            }
            (ColorMode::Degree, Some(m)) => {
                let v: Vec<f32> = faces
                    .iter()
                    .map(|(h, _)| m.deformation_degree[*h as usize])
                    .collect();
                let r = opts
                    .degree_range
                    .unwrap_or_else(|| colormap::robust_range(&v, 1e-3));
                (v, r)
            }
            _ => (vec![0.0; faces.len()], 1.0),
        };
        s.color_range = range;
        if opts.visible[2] {
            let tris: Vec<[u32; 3]> = faces
                .iter()
                .flat_map(|(_, q)| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
                .collect();
            let normals = vertex_normals(&fat_x, &tris);
            for ((_, q), val) in faces.iter().zip(&values) {
                let c = match opts.color_mode {
                    ColorMode::None => colormap::SKIN,
                    ColorMode::Area if metrics.is_some() => colormap::area_color(*val, range),
                    ColorMode::Degree if metrics.is_some() => colormap::degree_color(*val, range),
                    _ => colormap::SKIN,
                };
                let base = s.vertices.len() as u32;
                for &i in q {
                    s.vertices.push(Vertex {
                        pos: fat_x[i as usize].to_array(),
                        normal: normals[i as usize].to_array(),
                        color: [c[0], c[1], c[2], opts.opacity[2]],
                    });
                }
                s.indices
                    .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
            }
        }
        s.ranges[2] = start..s.indices.len() as u32;
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        // The posed bones and skin, and whatever else is drawn (muscles may reach past both).
        let posed_bones = bones.iter().flatten().copied();
        let drawn = s.vertices.iter().map(|v| Vec3::from_array(v.pos));
        for p in fat_x.iter().copied().chain(posed_bones).chain(drawn) {
            lo = lo.min(p);
            hi = hi.max(p);
        }
        s.bounds = (lo, hi);
        s
    }

    /// The muscle whose triangles include index position `at` (into `indices`).
    pub fn muscle_of_index(&self, at: u32) -> Option<usize> {
        let k = self.muscle_ranges.partition_point(|(_, r)| r.end <= at);
        self.muscle_ranges
            .get(k)
            .filter(|(_, r)| r.contains(&at))
            .map(|(i, _)| *i)
    }

    /// Triangle count of a layer.
    pub fn triangles(&self, layer: Layer) -> usize {
        self.ranges[layer as usize].len() / 3
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use myoslice::SimulationConfig;

    #[test]
    fn the_scene_of_a_flexed_phantom_has_its_layers_visibility_colours_and_bounds() {
        let mut sim = Simulation::phantom(SimulationConfig::default()).expect("phantom");
        sim.set_knee(1.2, 0.0).expect("knee");
        let lat = sim.lattice();
        let all = SceneMesh::build(&sim, &SceneOptions::default());
        let bone_tris: usize = lat.bones.iter().map(|b| b.mesh.triangles.len()).sum();
        let muscle_tris: usize = lat.muscles.iter().map(|m| m.mesh.triangles.len()).sum();
        assert_eq!(all.triangles(Layer::Bone), bone_tris);
        assert_eq!(all.triangles(Layer::Muscle), muscle_tris);
        assert_eq!(all.triangles(Layer::Skin), 2 * lat.fat.outer_faces().len());
        assert_eq!(all.ranges[2].end as usize, all.indices.len());
        assert!(
            all.indices
                .iter()
                .all(|&i| (i as usize) < all.vertices.len())
        );
        let (lo, hi) = all.bounds;
        for v in &all.vertices {
            let p = Vec3::from_array(v.pos);
            assert!(
                p.cmpge(lo - 1e-5).all() && p.cmple(hi + 1e-5).all(),
                "{p} outside"
            );
            assert!((Vec3::from_array(v.normal).length() - 1.0).abs() < 1e-3);
        }
        // Hidden layers draw nothing; the others keep their triangles.
        let skin_only = SceneMesh::build(
            &sim,
            &SceneOptions {
                visible: [false, false, true],
                ..SceneOptions::default()
            },
        );
        assert_eq!(skin_only.triangles(Layer::Bone), 0);
        assert_eq!(skin_only.triangles(Layer::Muscle), 0);
        assert_eq!(skin_only.triangles(Layer::Skin), all.triangles(Layer::Skin));
        // After a flexion the area colours leave the skin colour somewhere; "none" nowhere.
        let skin_colours = |mode| {
            let m = SceneMesh::build(
                &sim,
                &SceneOptions {
                    color_mode: mode,
                    visible: [false, false, true],
                    ..SceneOptions::default()
                },
            );
            m.vertices
                .iter()
                .filter(|v| v.color[..3] != colormap::SKIN[..3])
                .count()
        };
        assert!(skin_colours(ColorMode::Area) > 100);
        assert_eq!(skin_colours(ColorMode::None), 0);
    }

    #[test]
    fn the_hovered_and_selected_muscles_are_tinted_and_their_triangles_map_back_to_them() {
        let mut config = SimulationConfig::default();
        config.tissue.enabled = false;
        let sim = Simulation::phantom(config).expect("phantom");
        let (hov, sel) = (2, 5);
        let m = SceneMesh::build(
            &sim,
            &SceneOptions {
                hovered_muscle: Some(hov),
                selected_muscle: Some(sel),
                ..SceneOptions::default()
            },
        );
        assert_eq!(m.muscle_ranges.len(), sim.muscles().len());
        for (i, r) in &m.muscle_ranges {
            let want = match *i {
                i if i == sel => colormap::SELECTED,
                i if i == hov => colormap::HOVERED,
                _ => colormap::MUSCLE,
            };
            for &k in &m.indices[r.start as usize..r.end as usize] {
                assert_eq!(m.vertices[k as usize].color[..3], want[..], "muscle {i}");
            }
            assert_eq!(m.muscle_of_index(r.start), Some(*i));
            assert_eq!(m.muscle_of_index(r.end - 1), Some(*i));
        }
        // Bone and skin indices belong to no muscle.
        assert_eq!(m.muscle_of_index(m.ranges[0].start), None);
        assert_eq!(m.muscle_of_index(m.ranges[2].start), None);
    }

    #[test]
    fn normals_of_a_tetrahedron_point_outward() {
        let v = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
        let t = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        let n = vertex_normals(&v, &t);
        let c = Vec3::splat(0.25);
        for (p, nn) in v.iter().zip(&n) {
            assert!((*p - c).dot(*nn) > 0.0);
        }
    }
}
