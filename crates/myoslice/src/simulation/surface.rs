//! The surfaces of a simulation now, per layer: what the viewer draws, Python reads and
//! the exporters write.

use std::str::FromStr;

use glam::Vec3;

use super::Simulation;
use crate::body::body_of_bone;
use crate::error::{Error, Result};
use crate::lattice::FatLattice;
use crate::tissue::CarriedTissue;

/// A surface layer of the body.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layer {
    /// Every bone, moved with its body.
    Bone,
    /// Every muscle, deformed (or carried rigidly by its origin bone without tissue).
    Muscle,
    /// The body surface: the outer faces of the fat.
    Skin,
}

impl Layer {
    /// All layers, inside out.
    pub const ALL: [Layer; 3] = [Layer::Bone, Layer::Muscle, Layer::Skin];

    /// The layer's name.
    pub fn name(self) -> &'static str {
        match self {
            Layer::Bone => "bone",
            Layer::Muscle => "muscle",
            Layer::Skin => "skin",
        }
    }
}

impl FromStr for Layer {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        Layer::ALL
            .into_iter()
            .find(|l| l.name() == s)
            .ok_or_else(|| Error::unknown_name("layer", s, Layer::ALL.iter().map(|l| l.name())))
    }
}

/// Triangles over their own vertices (m, world).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Surface {
    /// Vertices.
    pub vertices: Vec<Vec3>,
    /// Triangles, outward.
    pub triangles: Vec<[u32; 3]>,
}

impl Surface {
    fn push(&mut self, vertices: &[Vec3], triangles: &[[u32; 3]]) {
        let base = self.vertices.len() as u32;
        self.vertices.extend_from_slice(vertices);
        self.triangles
            .extend(triangles.iter().map(|t| t.map(|i| i + base)));
    }
}

impl FatLattice {
    /// The body surface on its own vertices: for each skin vertex the fat vertex it is,
    /// and the skin triangles over skin vertices.
    pub fn skin_mesh(&self) -> (Vec<u32>, Vec<[u32; 3]>) {
        let mut map = vec![u32::MAX; self.vertices.len()];
        let mut used = Vec::new();
        let triangles = self
            .surface_triangles()
            .iter()
            .map(|t| {
                t.map(|i| {
                    let i = i as usize;
                    if map[i] == u32::MAX {
                        map[i] = used.len() as u32;
                        used.push(i as u32);
                    }
                    map[i]
                })
            })
            .collect();
        (used, triangles)
    }
}

impl Simulation {
    /// Vertices of bone `i` (lattice order) now, moved with its body.
    pub fn bone_vertices(&self, i: usize) -> Vec<Vec3> {
        let b = &self.lattice().bones[i];
        let body = body_of_bone(&b.name);
        b.mesh
            .vertices
            .iter()
            .map(|p| self.frames().point(body, *p))
            .collect()
    }

    /// Vertices of muscle `i` (simulation order) now: its deformed shape, or without
    /// tissue its rest shape carried by its origin bone.
    pub fn muscle_vertices(&self, i: usize) -> Vec<Vec3> {
        match self.tissue() {
            Some(t) => t.muscles[i].current.clone(),
            None => {
                let m = &self.muscles()[i];
                let body = m.chain.origin.body;
                self.lattice().muscles[m.lattice_index]
                    .mesh
                    .vertices
                    .iter()
                    .map(|p| self.frames().point(body, *p))
                    .collect()
            }
        }
    }

    /// Fat vertices now (the rest shape without tissue).
    pub fn fat_vertices(&self) -> &[Vec3] {
        self.tissue()
            .map_or(&self.lattice().fat.vertices[..], |t| t.fat_vertices())
    }

    /// One layer's surface now: the tissue's layers as its last update left them.
    ///
    /// ```no_run
    /// use myoslice::prelude::*;
    /// use myoslice::simulation::Layer;
    /// let sim = Simulation::phantom(SimulationConfig::default())?;
    /// let skin = sim.surface(Layer::Skin);
    /// println!("{} skin triangles", skin.triangles.len());
    /// # Ok::<(), myoslice::Error>(())
    /// ```
    pub fn surface(&self, layer: Layer) -> Surface {
        self.surface_with(layer, None)
    }

    /// [`Self::surface`] with the tissue's layers carried with the bones from its last
    /// update to now ([`Self::carried_tissue`]): what the viewer draws between updates.
    pub fn carried_surface(&self, layer: Layer) -> Surface {
        let carried = match layer {
            Layer::Bone => None,
            Layer::Muscle | Layer::Skin => self.carried_tissue(),
        };
        self.surface_with(layer, carried.as_ref())
    }

    fn surface_with(&self, layer: Layer, carried: Option<&CarriedTissue>) -> Surface {
        let lat = self.lattice();
        let mut s = Surface::default();
        match layer {
            Layer::Bone => {
                for (i, b) in lat.bones.iter().enumerate() {
                    s.push(&self.bone_vertices(i), &b.mesh.triangles);
                }
            }
            Layer::Muscle => {
                for (i, m) in self.muscles().iter().enumerate() {
                    let triangles = &lat.muscles[m.lattice_index].mesh.triangles;
                    match carried {
                        Some(c) => s.push(&c.muscles[i], triangles),
                        None => s.push(&self.muscle_vertices(i), triangles),
                    }
                }
            }
            Layer::Skin => {
                let (used, triangles) = lat.fat.skin_mesh();
                let x = carried.map_or_else(|| self.fat_vertices(), |c| &c.fat[..]);
                s.vertices = used.iter().map(|&i| x[i as usize]).collect();
                s.triangles = triangles;
            }
        }
        s
    }
}
