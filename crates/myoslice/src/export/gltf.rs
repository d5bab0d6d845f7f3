//! Animated glTF binary (`.glb`) for Blender: the body surface with one morph target per
//! frame (step-keyed weights), and the bones, the shank's turning about the knee. Metres,
//! Y up as glTF requires (our +z up becomes +y, our +y anterior becomes −z).

use glam::{Quat, Vec3};
use serde_json::{Value, json};

/// Our frame (z up) to glTF's (y up).
pub fn to_gltf(p: Vec3) -> [f32; 3] {
    [p.x, p.z, -p.y]
}

/// A mesh with one morph target per frame.
#[derive(Debug, Clone, Default)]
pub struct MorphMesh {
    /// Name.
    pub name: String,
    /// Base positions (frame 0).
    pub base: Vec<Vec3>,
    /// Triangles.
    pub triangles: Vec<[u32; 3]>,
    /// Positions of every later frame (same vertex count).
    pub frames: Vec<Vec<Vec3>>,
    /// RGB colour.
    pub color: [f32; 3],
}

/// A rigid mesh turning about a pivot.
#[derive(Debug, Clone, Default)]
pub struct RigidMesh {
    /// Name.
    pub name: String,
    /// Positions (rest, world).
    pub vertices: Vec<Vec3>,
    /// Triangles.
    pub triangles: Vec<[u32; 3]>,
    /// Pivot (world).
    pub pivot: Vec3,
    /// Rotation at every frame (world).
    pub rotations: Vec<Quat>,
    /// RGB colour.
    pub color: [f32; 3],
}

struct Bin {
    data: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Bin {
    fn push(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while !self.data.len().is_multiple_of(4) {
            self.data.push(0);
        }
        let offset = self.data.len();
        self.data.extend_from_slice(bytes);
        let mut v = json!({"buffer": 0, "byteOffset": offset, "byteLength": bytes.len()});
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.views.push(v);
        self.views.len() - 1
    }

    fn vec3(&mut self, v: &[[f32; 3]], target: bool) -> usize {
        let bytes: Vec<u8> = v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.push(&bytes, target.then_some(34962));
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for p in v {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        if v.is_empty() {
            (lo, hi) = ([0.0; 3], [0.0; 3]);
        }
        self.accessors.push(json!({"bufferView": view, "componentType": 5126, "count": v.len(), "type": "VEC3", "min": lo, "max": hi}));
        self.accessors.len() - 1
    }

    fn indices(&mut self, t: &[[u32; 3]]) -> usize {
        let bytes: Vec<u8> = t.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.push(&bytes, Some(34963));
        self.accessors.push(json!({"bufferView": view, "componentType": 5125, "count": t.len() * 3, "type": "SCALAR"}));
        self.accessors.len() - 1
    }

    fn scalars(&mut self, v: &[f32], minmax: bool) -> usize {
        let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.push(&bytes, None);
        let mut a =
            json!({"bufferView": view, "componentType": 5126, "count": v.len(), "type": "SCALAR"});
        if minmax && !v.is_empty() {
            a["min"] = json!([v.iter().copied().fold(f32::INFINITY, f32::min)]);
            a["max"] = json!([v.iter().copied().fold(f32::NEG_INFINITY, f32::max)]);
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    fn vec4(&mut self, v: &[[f32; 4]]) -> usize {
        let bytes: Vec<u8> = v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.push(&bytes, None);
        self.accessors.push(
            json!({"bufferView": view, "componentType": 5126, "count": v.len(), "type": "VEC4"}),
        );
        self.accessors.len() - 1
    }
}

/// Builds the GLB bytes for frames at `times` (s).
pub fn encode_glb(times: &[f32], morphs: &[MorphMesh], rigids: &[RigidMesh]) -> Vec<u8> {
    let mut bin = Bin {
        data: Vec::new(),
        views: Vec::new(),
        accessors: Vec::new(),
    };
    let mut meshes = Vec::new();
    let mut nodes = Vec::new();
    let mut materials = Vec::new();
    let mut channels = Vec::new();
    let mut samplers = Vec::new();
    let time_acc = bin.scalars(times, true);
    for m in morphs {
        let base: Vec<[f32; 3]> = m.base.iter().map(|p| to_gltf(*p)).collect();
        let pos = bin.vec3(&base, true);
        let idx = bin.indices(&m.triangles);
        let targets: Vec<Value> = m
            .frames
            .iter()
            .map(|f| {
                let d: Vec<[f32; 3]> = f
                    .iter()
                    .zip(&m.base)
                    .map(|(p, b)| to_gltf(*p - *b))
                    .collect();
                json!({"POSITION": bin.vec3(&d, true)})
            })
            .collect();
        materials.push(json!({"name": m.name, "pbrMetallicRoughness": {"baseColorFactor": [m.color[0], m.color[1], m.color[2], 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.7}, "doubleSided": true}));
        let n_targets = targets.len();
        meshes.push(json!({"name": m.name, "primitives": [{"attributes": {"POSITION": pos}, "indices": idx, "material": materials.len() - 1, "targets": targets}], "weights": vec![0.0; n_targets]}));
        nodes.push(json!({"name": m.name, "mesh": meshes.len() - 1}));
        if n_targets > 0 {
            // Frame k (k >= 1) shows target k-1 at full weight; frame 0 shows the base.
            let mut w = Vec::with_capacity(times.len() * n_targets);
            for k in 0..times.len() {
                for t in 0..n_targets {
                    w.push(if k >= 1 && t == k - 1 { 1.0 } else { 0.0 });
                }
            }
            let out = bin.scalars(&w, false);
            samplers.push(json!({"input": time_acc, "output": out, "interpolation": "STEP"}));
            channels.push(json!({"sampler": samplers.len() - 1, "target": {"node": nodes.len() - 1, "path": "weights"}}));
        }
    }
    for r in rigids {
        let local: Vec<[f32; 3]> = r.vertices.iter().map(|p| to_gltf(*p - r.pivot)).collect();
        let pos = bin.vec3(&local, true);
        let idx = bin.indices(&r.triangles);
        materials.push(json!({"name": r.name, "pbrMetallicRoughness": {"baseColorFactor": [r.color[0], r.color[1], r.color[2], 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.5}}));
        meshes.push(json!({"name": r.name, "primitives": [{"attributes": {"POSITION": pos}, "indices": idx, "material": materials.len() - 1}]}));
        nodes.push(
            json!({"name": r.name, "mesh": meshes.len() - 1, "translation": to_gltf(r.pivot)}),
        );
        if !r.rotations.is_empty() {
            // Rotations in the y-up frame: the axis is mapped like a vector.
            let q: Vec<[f32; 4]> = r
                .rotations
                .iter()
                .map(|q| {
                    let a = to_gltf(Vec3::new(q.x, q.y, q.z));
                    [a[0], a[1], a[2], q.w]
                })
                .collect();
            let out = bin.vec4(&q);
            samplers.push(json!({"input": time_acc, "output": out, "interpolation": "LINEAR"}));
            channels.push(json!({"sampler": samplers.len() - 1, "target": {"node": nodes.len() - 1, "path": "rotation"}}));
        }
    }
    while !bin.data.len().is_multiple_of(4) {
        bin.data.push(0);
    }
    let mut doc = json!({
        "asset": {"version": "2.0", "generator": "myoslice"},
        "scene": 0,
        "scenes": [{"nodes": (0..nodes.len()).collect::<Vec<_>>()}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "buffers": [{"byteLength": bin.data.len()}],
        "bufferViews": bin.views,
        "accessors": bin.accessors,
    });
    if !channels.is_empty() {
        doc["animations"] = json!([{"name": "motion", "channels": channels, "samplers": samplers}]);
    }
    let mut json_bytes = serde_json::to_vec(&doc).unwrap_or_default();
    while !json_bytes.len().is_multiple_of(4) {
        json_bytes.push(b' ');
    }
    let total = 12 + 8 + json_bytes.len() + 8 + bin.data.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json_bytes.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json_bytes);
    out.extend_from_slice(&(bin.data.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin.data);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_glb_has_a_valid_header_and_json() {
        let m = MorphMesh {
            name: "skin".into(),
            base: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            triangles: vec![[0, 1, 2]],
            frames: vec![vec![Vec3::ZERO, Vec3::X, Vec3::Y * 2.0]],
            color: [1.0, 0.8, 0.7],
        };
        let g = encode_glb(&[0.0, 0.1], &[m], &[]);
        assert_eq!(&g[0..4], b"glTF");
        let total = u32::from_le_bytes([g[8], g[9], g[10], g[11]]) as usize;
        assert_eq!(total, g.len());
        let jlen = u32::from_le_bytes([g[12], g[13], g[14], g[15]]) as usize;
        let doc: Value = serde_json::from_slice(&g[20..20 + jlen]).unwrap();
        assert_eq!(doc["asset"]["version"], "2.0");
        assert_eq!(doc["animations"][0]["samplers"][0]["interpolation"], "STEP");
    }
}
