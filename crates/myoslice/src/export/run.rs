//! Writing a run: VTU frames with a PVD series (ParaView), an animated GLB (Blender), a
//! time series CSV and a summary JSON. Every frame is complete on disk when written, so an
//! interrupted run leaves valid files.

use std::io::Write;
use std::path::{Path, PathBuf};

use glam::{Quat, Vec3};
use serde::Serialize;

use super::body_vtu::{BodyPositions, FatScalars, body_vtu};
use super::gltf::{MorphMesh, RigidMesh, encode_glb};
use super::vtu::{write_atomic, write_pvd};
use crate::body::{BodyId, body_of_bone};
use crate::error::{Error, Result};
use crate::simulation::Simulation;
use crate::tissue::{GuardTally, TissueAudit};

/// What to write.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RunOutputs {
    /// VTU frames + PVD series.
    pub vtu: bool,
    /// Animated GLB at the end.
    pub glb: bool,
    /// Every soundness check of the tissue after each of its updates (`audit.csv`, and
    /// the worst and last in the summary): slow, about a second an update.
    pub audit: bool,
}

/// Extremes and totals of a run (`summary.json`).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct RunSummary {
    /// Simulated time (s).
    pub duration_s: f64,
    /// Muscle steps taken.
    pub steps: u64,
    /// Output frames written.
    pub frames: usize,
    /// Time series rows written.
    pub rows: usize,
    /// Final knee angle (deg).
    pub final_knee_angle_deg: f64,
    /// Smallest and largest knee angle over the time series (deg).
    pub knee_angle_range_deg: [f64; 2],
    /// Largest knee speed (deg/s).
    pub max_knee_speed_deg_s: f64,
    /// Smallest fat element volume ratio over the frames.
    pub min_fat_volume_ratio: f64,
    /// Largest |area change| over the frames.
    pub max_abs_area_change: f64,
    /// Smallest and largest muscle volume ratio over the frames.
    pub muscle_volume_ratio_range: [f64; 2],
    /// Most fat elements with a folded corner in one frame (a corner Jacobian at or below
    /// zero: the hexahedra ParaView's and VTK's quality filters call invalid).
    pub inverted_elements: usize,
    /// Fat elements with a folded corner in the last frame (whether the fat came back).
    pub final_inverted_elements: usize,
    /// How often the validity guard, the tissue's last resort, moved fat back toward
    /// the knee fold over the run (zeros without tissue).
    pub guard: GuardTally,
    /// Wall time of the run (s), an audit's left out.
    pub wall_time_s: f64,
    /// Simulated seconds per wall second.
    pub realtime_factor: f64,
    /// Of the wall time, the part of `step` outside tissue updates (s): the muscles and
    /// the skeleton, less their steps that ran beside an update's guard. The rest is the
    /// build, the tissue and the writing of outputs.
    pub muscles_wall_time_s: f64,
    /// Of the wall time, the part spent on the tissue updates inside `step` (s); the
    /// updates for output frames are not in it.
    pub tissue_wall_time_s: f64,
    /// What the model's build could not take from the catalogue
    /// ([`Simulation::warnings`]).
    pub warnings: Vec<String>,
    /// The tissue audited after every update, when the run was asked to (None otherwise,
    /// or without tissue).
    pub audit: Option<RunAudit>,
}

/// A run's tissue, audited after every update ([`Simulation::audit`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RunAudit {
    /// Tissue updates audited.
    pub updates: u64,
    /// The worst of each check over them.
    pub worst: TissueAudit,
    /// The last update's (after the run: whether the tissue came back).
    pub last: TissueAudit,
    /// Wall time the audits took (s), left out of the run's wall time.
    pub wall_time_s: f64,
}

/// An open run folder.
#[derive(Debug)]
pub struct RunWriter {
    dir: PathBuf,
    outputs: RunOutputs,
    csv: std::io::BufWriter<std::fs::File>,
    /// `audit.csv`, when auditing, and the tissue update audited last (None before the
    /// first).
    audit_csv: Option<(std::io::BufWriter<std::fs::File>, Option<u64>)>,
    pvd: Vec<(f64, String)>,
    glb_times: Vec<f32>,
    skin_frames: Vec<Vec<Vec3>>,
    shank_rot: Vec<Quat>,
    summary: RunSummary,
}

fn werr(p: &Path, e: std::io::Error) -> Error {
    Error::Write {
        path: p.to_path_buf(),
        source: e,
    }
}

impl RunWriter {
    /// Creates the folder and writes the first row and frame.
    pub fn create(dir: &Path, sim: &Simulation, outputs: RunOutputs) -> Result<Self> {
        std::fs::create_dir_all(dir).map_err(|e| werr(dir, e))?;
        let csv_path = dir.join("timeseries.csv");
        let f = std::fs::File::create(&csv_path).map_err(|e| werr(&csv_path, e))?;
        let mut csv = std::io::BufWriter::new(f);
        let mut header = String::from("time_s,knee_angle_deg,knee_velocity_deg_s,knee_torque_nm");
        for n in sim.muscle_names() {
            header += &format!(",{n}_excitation,{n}_activation,{n}_force_n");
        }
        writeln!(csv, "{header}").map_err(|e| werr(&csv_path, e))?;
        let audit_csv = if outputs.audit && sim.tissue().is_some() {
            let p = dir.join("audit.csv");
            let f = std::fs::File::create(&p).map_err(|e| werr(&p, e))?;
            let mut f = std::io::BufWriter::new(f);
            let head = TissueAudit::CSV_HEADER;
            writeln!(f, "time_s,knee_angle_deg,tissue_update,{head}").map_err(|e| werr(&p, e))?;
            Some((f, None))
        } else {
            None
        };
        let mut w = Self {
            dir: dir.to_path_buf(),
            outputs,
            csv,
            audit_csv,
            pvd: Vec::new(),
            glb_times: Vec::new(),
            skin_frames: Vec::new(),
            shank_rot: Vec::new(),
            summary: RunSummary {
                duration_s: 0.0,
                steps: 0,
                frames: 0,
                rows: 0,
                final_knee_angle_deg: 0.0,
                knee_angle_range_deg: [f64::INFINITY, f64::NEG_INFINITY],
                max_knee_speed_deg_s: 0.0,
                min_fat_volume_ratio: 1.0,
                max_abs_area_change: 0.0,
                muscle_volume_ratio_range: [1.0, 1.0],
                inverted_elements: 0,
                final_inverted_elements: 0,
                guard: GuardTally::default(),
                wall_time_s: 0.0,
                realtime_factor: 0.0,
                muscles_wall_time_s: 0.0,
                tissue_wall_time_s: 0.0,
                warnings: sim.warnings().to_vec(),
                audit: None,
            },
        };
        w.audit(sim)?;
        w.row(sim)?;
        w.frame(sim)?;
        Ok(w)
    }

    /// Appends one time-series row (flushed at once).
    pub fn row(&mut self, sim: &Simulation) -> Result<()> {
        let a = sim.knee_angle().to_degrees();
        let v = sim.knee_velocity().to_degrees();
        let mut line = format!("{:.6},{a:.6},{v:.6},{:.6}", sim.time(), sim.knee_torque());
        for m in sim.muscles() {
            line += &format!(",{:.6},{:.6},{:.6}", m.excitation, m.activation, m.force);
        }
        let p = self.dir.join("timeseries.csv");
        writeln!(self.csv, "{line}").map_err(|e| werr(&p, e))?;
        self.csv.flush().map_err(|e| werr(&p, e))?;
        let s = &mut self.summary;
        s.rows += 1;
        s.knee_angle_range_deg = [
            s.knee_angle_range_deg[0].min(a),
            s.knee_angle_range_deg[1].max(a),
        ];
        s.max_knee_speed_deg_s = s.max_knee_speed_deg_s.max(v.abs());
        s.final_knee_angle_deg = a;
        s.duration_s = sim.time();
        Ok(())
    }

    /// Audits the tissue if the run asked for it and it has updated since the last audit:
    /// one row of `audit.csv`, and the summary's worst and last. Call after every step.
    pub fn audit(&mut self, sim: &Simulation) -> Result<()> {
        let (Some((csv, seen)), Some(t)) = (self.audit_csv.as_mut(), sim.tissue()) else {
            return Ok(());
        };
        if *seen == Some(t.updates()) {
            return Ok(());
        }
        *seen = Some(t.updates());
        let start = web_time::Instant::now();
        let a = t.audit(sim.frames());
        let line = format!(
            "{:.6},{:.6},{},{}",
            sim.time(),
            sim.knee_angle().to_degrees(),
            t.updates(),
            a.csv_row()
        );
        let p = self.dir.join("audit.csv");
        writeln!(csv, "{line}").map_err(|e| werr(&p, e))?;
        csv.flush().map_err(|e| werr(&p, e))?;
        let took = start.elapsed().as_secs_f64();
        let s = &mut self.summary.audit;
        *s = Some(match s.take() {
            Some(r) => RunAudit {
                updates: r.updates + 1,
                worst: r.worst.worse(&a),
                last: a,
                wall_time_s: r.wall_time_s + took,
            },
            None => RunAudit {
                updates: 1,
                worst: a,
                last: a,
                wall_time_s: took,
            },
        });
        Ok(())
    }

    /// Writes one output frame.
    pub fn frame(&mut self, sim: &Simulation) -> Result<()> {
        let k = self.summary.frames;
        let lat = sim.lattice();
        let frames = sim.frames();
        if let Some(m) = sim.tissue_metrics() {
            let s = &mut self.summary;
            s.min_fat_volume_ratio = s.min_fat_volume_ratio.min(f64::from(m.min_volume_ratio));
            s.max_abs_area_change = s.max_abs_area_change.max(f64::from(m.max_abs_area_change));
            s.inverted_elements = s.inverted_elements.max(m.inverted);
            s.final_inverted_elements = m.inverted;
            for r in &m.muscle_volume_ratio {
                s.muscle_volume_ratio_range = [
                    s.muscle_volume_ratio_range[0].min(f64::from(*r)),
                    s.muscle_volume_ratio_range[1].max(f64::from(*r)),
                ];
            }
        }
        let fat_x: Vec<Vec3> = sim.fat_vertices().to_vec();
        if self.outputs.vtu {
            let bones: Vec<Vec<Vec3>> =
                (0..lat.bones.len()).map(|i| sim.bone_vertices(i)).collect();
            let muscles: Vec<Vec<Vec3>> = match sim.tissue() {
                Some(t) => t.muscles.iter().map(|m| m.current.clone()).collect(),
                None => sim
                    .muscles()
                    .iter()
                    .map(|m| lat.muscles[m.lattice_index].mesh.vertices.clone())
                    .collect(),
            };
            let scalars = sim.tissue_metrics().map(|m| FatScalars {
                area_change: &m.area_change,
                deformation_degree: &m.deformation_degree,
                volume_ratio: &m.volume_ratio,
            });
            let mesh = body_vtu(
                lat,
                BodyPositions {
                    bones: &bones,
                    muscles: &muscles,
                    fat: &fat_x,
                },
                scalars,
            );
            let name = format!("frame_{k:04}.vtu");
            mesh.write(&self.dir.join(&name))?;
            self.pvd.push((sim.time(), name));
            write_pvd(&self.dir.join("series.pvd"), &self.pvd)?;
        }
        if self.outputs.glb {
            self.glb_times.push(sim.time() as f32);
            self.skin_frames.push(fat_x);
            self.shank_rot.push(frames.shank.0);
        }
        self.summary.frames += 1;
        Ok(())
    }

    /// Writes the GLB and the summary; returns the summary. `wall_s` is the run's wall time,
    /// its audits included: the summary leaves them out.
    pub fn finish(mut self, sim: &Simulation, wall_s: f64) -> Result<RunSummary> {
        let wall_s = wall_s - self.summary.audit.map_or(0.0, |a| a.wall_time_s);
        self.summary.steps = sim.steps();
        self.summary.duration_s = sim.time();
        self.summary.wall_time_s = wall_s;
        self.summary.realtime_factor = if wall_s > 0.0 {
            sim.time() / wall_s
        } else {
            0.0
        };
        self.summary.muscles_wall_time_s = sim.timers().muscles_wall_s();
        self.summary.tissue_wall_time_s = sim.timers().tissue_wall_s;
        self.summary.guard = sim.tissue().map(|t| t.guard_tally()).unwrap_or_default();
        if self.summary.knee_angle_range_deg[0] > self.summary.knee_angle_range_deg[1] {
            self.summary.knee_angle_range_deg = [0.0, 0.0];
        }
        if self.outputs.glb && !self.skin_frames.is_empty() {
            let lat = sim.lattice();
            // The skin: only the outer layer, on its own vertices.
            let (used, tri) = lat.fat.skin_mesh();
            let pick = |x: &Vec<Vec3>| used.iter().map(|&i| x[i as usize]).collect::<Vec<Vec3>>();
            let skin = MorphMesh {
                name: "skin".into(),
                base: pick(&self.skin_frames[0]),
                triangles: tri,
                frames: self.skin_frames[1..].iter().map(pick).collect(),
                color: [0.93, 0.76, 0.64],
            };
            let knee = sim.skeleton().knee().point;
            let mut rigids = Vec::new();
            for body in [BodyId::Thigh, BodyId::Shank] {
                let (mut v, mut t) = (Vec::new(), Vec::new());
                for b in lat.bones.iter().filter(|b| body_of_bone(&b.name) == body) {
                    let base = v.len() as u32;
                    v.extend_from_slice(&b.mesh.vertices);
                    t.extend(b.mesh.triangles.iter().map(|x| x.map(|i| i + base)));
                }
                rigids.push(RigidMesh {
                    name: if body == BodyId::Thigh {
                        "pelvis_femur".into()
                    } else {
                        "shank_bones".into()
                    },
                    vertices: v,
                    triangles: t,
                    pivot: knee,
                    rotations: if body == BodyId::Shank {
                        self.shank_rot.clone()
                    } else {
                        Vec::new()
                    },
                    color: [0.93, 0.91, 0.84],
                });
            }
            let bytes = encode_glb(&self.glb_times, &[skin], &rigids);
            write_atomic(&self.dir.join("motion.glb"), &bytes)?;
        }
        let json = serde_json::to_string_pretty(&self.summary).unwrap_or_default();
        write_atomic(&self.dir.join("summary.json"), json.as_bytes())?;
        Ok(self.summary)
    }
}
