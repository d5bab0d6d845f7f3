//! Python bindings of myoslice: `myoslice._myoslice`. Thin: every behaviour lives in the
//! core crate; this file converts arguments, arrays and errors.

mod arrays;
mod config;
mod errors;
mod pool;
mod render;
mod scenario_run;
mod sources;

use std::path::PathBuf;

use myoslice::muscle::MuscleCatalogue;
use myoslice::prelude::*;
use myoslice::simulation::{Layer, SimulationState};
use numpy::{PyArray1, PyArray3, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use arrays::{
    SurfaceArrays, breach_dict, check_path, excitation_pairs, metric_array, reach_dict, tri_array,
    vec3_array,
};
use config::ConfigArgs;
use errors::{Kind, OrPy, py_err};

/// A checkpoint of a simulation (`Simulation.state()` / `set_state()`).
#[pyclass(name = "State", module = "myoslice._myoslice", frozen)]
struct PyState {
    inner: SimulationState,
}

#[pymethods]
impl PyState {
    /// Simulated time of the checkpoint (s).
    #[getter]
    fn time(&self) -> f64 {
        self.inner.time()
    }

    fn __repr__(&self) -> String {
        format!("State(time={:.6})", self.inner.time())
    }
}

/// A muscle-driven lower limb: step it, excite its muscles, read the knee, the muscles and
/// the deformed tissue as numpy arrays.
#[pyclass(name = "Simulation", module = "myoslice._myoslice")]
struct PySimulation {
    sim: Simulation,
    offscreen: render::Target,
}

#[pymethods]
impl PySimulation {
    /// The built-in lower-limb phantom (no files needed). Units are SI.
    #[staticmethod]
    #[pyo3(signature = (*, body_mass_kg = 60.0, height_m = 1.65, muscle_model = "hill", tendon = "rigid", tissue = true, tissue_rate_hz = 30.0, tissue_iterations = None, initial_knee_deg = 0.0, max_step_s = 0.001, chain_tether = None, chain_tether_release_n = None, chain_contact = None, muscle_contact = None, fat_constraints = None, voxel_mm = None))]
    #[allow(clippy::too_many_arguments)]
    fn phantom(
        py: Python<'_>,
        body_mass_kg: f64,
        height_m: f64,
        muscle_model: &str,
        tendon: &str,
        tissue: bool,
        tissue_rate_hz: f64,
        tissue_iterations: Option<i64>,
        initial_knee_deg: f64,
        max_step_s: f64,
        chain_tether: Option<f64>,
        chain_tether_release_n: Option<f64>,
        chain_contact: Option<bool>,
        muscle_contact: Option<bool>,
        fat_constraints: Option<bool>,
        voxel_mm: Option<f64>,
    ) -> PyResult<Self> {
        let c = ConfigArgs {
            body_mass_kg,
            height_m,
            muscle_model,
            tendon,
            tissue,
            tissue_rate_hz,
            tissue_iterations,
            initial_knee_deg,
            max_step_s,
            chain_tether,
            chain_tether_release_n,
            chain_contact,
            muscle_contact,
            fat_constraints,
        }
        .config(py)?;
        let sim = crate::pool::detach(py, move || -> myoslice::Result<Simulation> {
            let (v, t) = Phantom { voxel_mm }.generate()?;
            let lat = Lattice::build(&v, &t, &BuildOptions::default())?;
            Simulation::new(lat, c, &MuscleCatalogue::default())
        })
        .or_py(py)?;
        Ok(Self {
            sim,
            offscreen: None,
        })
    }

    /// A label volume (NIfTI-1/-2 or NRRD) or a PNG stack (its folder or manifest), told
    /// apart by content, with its label table (JSON or TOML) or a segmentation tool's
    /// label list (ITK-SNAP, 3D Slicer), whose names are mapped onto known structures;
    /// without one, a 3D Slicer segmentation's own segment names. `unmapped` ("error",
    /// "fat" or "ignore") says what to do with a name none is known by; `names` is the
    /// user's own names file (TOML).
    #[staticmethod]
    #[pyo3(signature = (volume, labels = None, *, unmapped = "error", names = None, slice_step = 5, rays = 48, body_mass_kg = 60.0, height_m = 1.65, muscle_model = "hill", tendon = "rigid", tissue = true, tissue_rate_hz = 30.0, tissue_iterations = None, initial_knee_deg = 0.0, max_step_s = 0.001, chain_tether = None, chain_tether_release_n = None, chain_contact = None, muscle_contact = None, fat_constraints = None))]
    #[allow(clippy::too_many_arguments)]
    fn from_nifti(
        py: Python<'_>,
        volume: PathBuf,
        labels: Option<PathBuf>,
        unmapped: &str,
        names: Option<PathBuf>,
        slice_step: usize,
        rays: usize,
        body_mass_kg: f64,
        height_m: f64,
        muscle_model: &str,
        tendon: &str,
        tissue: bool,
        tissue_rate_hz: f64,
        tissue_iterations: Option<i64>,
        initial_knee_deg: f64,
        max_step_s: f64,
        chain_tether: Option<f64>,
        chain_tether_release_n: Option<f64>,
        chain_contact: Option<bool>,
        muscle_contact: Option<bool>,
        fat_constraints: Option<bool>,
    ) -> PyResult<Self> {
        let mapping = sources::mapping(py, unmapped, names.as_deref())?;
        let c = ConfigArgs {
            body_mass_kg,
            height_m,
            muscle_model,
            tendon,
            tissue,
            tissue_rate_hz,
            tissue_iterations,
            initial_knee_deg,
            max_step_s,
            chain_tether,
            chain_tether_release_n,
            chain_contact,
            muscle_contact,
            fat_constraints,
        }
        .config(py)?;
        let build = BuildOptions {
            reduction: SliceReduction {
                slice_step,
                pixel_mm: None,
            },
            rays,
            ..BuildOptions::default()
        };
        let sim = sources::simulation_from_file(py, volume, labels, mapping, build, c)?;
        sources::warn(py, sim.warnings())?;
        Ok(Self {
            sim,
            offscreen: None,
        })
    }

    /// Any file myoslice reads, told apart by its content: a scenario (built as
    /// `from_scenario`, which takes no other argument), or a label volume or PNG stack
    /// (as `from_nifti`, with the same keyword arguments).
    #[staticmethod]
    #[pyo3(signature = (path, labels = None, **kwargs))]
    fn from_file(
        py: Python<'_>,
        path: PathBuf,
        labels: Option<PathBuf>,
        kwargs: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Py<Self>> {
        let ty = py.get_type::<Self>();
        if sources::is_scenario(py, &path)? {
            let extra = kwargs.map_or(0, |k| k.len());
            if labels.is_some() || extra > 0 {
                return Err(py_err(
                    py,
                    Kind::Invalid,
                    format!(
                        "{} is a scenario, which brings its own model and settings: give it \
                         alone",
                        path.display()
                    ),
                ));
            }
            return Ok(ty.getattr("from_scenario")?.call1((path,))?.extract()?);
        }
        Ok(ty
            .getattr("from_nifti")?
            .call((path, labels), kwargs)?
            .extract()?)
    }

    /// A scenario file (TOML): model, body, muscle model, excitation schedules.
    #[staticmethod]
    fn from_scenario(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        check_path(py, &path, "scenario")?;
        let sim = crate::pool::detach(py, move || Scenario::from_path(&path)?.build()).or_py(py)?;
        sources::warn(py, sim.warnings())?;
        Ok(Self {
            sim,
            offscreen: None,
        })
    }

    /// Advances `n` steps of `dt` seconds (the GIL is released meanwhile).
    #[pyo3(signature = (dt = 0.001, n = 1))]
    fn step(&mut self, py: Python<'_>, dt: f64, n: i64) -> PyResult<()> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(py_err(
                py,
                Kind::Invalid,
                format!("dt = {dt}: expected a finite step > 0 s"),
            ));
        }
        if n < 1 {
            return Err(py_err(
                py,
                Kind::Invalid,
                format!("n = {n}: expected at least one step"),
            ));
        }
        let sim = &mut self.sim;
        crate::pool::detach(py, move || -> myoslice::Result<()> {
            for _ in 0..n {
                sim.step(dt)?;
            }
            Ok(())
        })
        .or_py(py)
    }

    /// Wall-clock time spent in `step` (the Rust side only) since the build or
    /// `reset_timers`, as a dict.
    #[getter]
    fn timers<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let t = self.sim.timers();
        let d = PyDict::new(py);
        d.set_item("calls", t.calls)?;
        d.set_item("steps", t.steps)?;
        d.set_item("tissue_updates", t.tissue_updates)?;
        d.set_item("simulated_s", t.simulated_s)?;
        d.set_item("wall_s", t.wall_s)?;
        d.set_item("tissue_wall_s", t.tissue_wall_s)?;
        d.set_item("muscles_wall_s", t.muscles_wall_s())?;
        d.set_item("realtime_factor", t.realtime_factor())?;
        let phases = PyDict::new(py);
        for (name, s) in t.tissue_phases.named() {
            phases.set_item(name, s)?;
        }
        d.set_item("tissue_phases_s", phases)?;
        Ok(d)
    }

    /// Starts the step timers from zero.
    fn reset_timers(&mut self) {
        self.sim.reset_timers();
    }

    /// Sets one muscle's excitation in [0, 1].
    fn set_excitation(&mut self, py: Python<'_>, name: &str, value: f64) -> PyResult<()> {
        self.sim.set_excitation(name, value).or_py(py)
    }

    /// Sets excitations from a dict {name: value} or an array in `muscle_names` order.
    fn set_excitations(&mut self, py: Python<'_>, values: &Bound<'_, PyAny>) -> PyResult<()> {
        if let Ok(d) = values.cast::<PyDict>() {
            let pairs = excitation_pairs(py, d, &self.sim)?;
            for (name, value) in pairs {
                self.sim.set_excitation(&name, value).or_py(py)?;
            }
            return Ok(());
        }
        let arr: PyReadonlyArray1<'_, f64> = match values.extract::<PyReadonlyArray1<'_, f64>>() {
            Ok(a) => a,
            Err(_) => {
                let np = py.import("numpy")?;
                let conv = np.call_method1("asarray", (values, "float64"));
                let conv = conv.map_err(|_| {
                    py_err(
                        py,
                        Kind::Invalid,
                        "excitations must be a dict or a 1-D array of numbers".into(),
                    )
                })?;
                if conv.getattr("ndim")?.extract::<usize>()? != 1 {
                    return Err(py_err(
                        py,
                        Kind::Invalid,
                        format!(
                            "excitations array must be 1-D with {} values",
                            self.sim.muscles().len()
                        ),
                    ));
                }
                conv.extract().map_err(|_| {
                    py_err(
                        py,
                        Kind::Invalid,
                        "excitations must be a 1-D float array".into(),
                    )
                })?
            }
        };
        let v = arr.as_array().to_vec();
        self.sim.set_excitations(&v).or_py(py)
    }

    /// Excitation of every muscle (copy).
    #[getter]
    fn excitations<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.sim.excitations())
    }

    /// Muscle names, in the order of every per-muscle array.
    #[getter]
    fn muscle_names(&self) -> Vec<String> {
        self.sim
            .muscle_names()
            .iter()
            .map(|s| s.to_string())
            .collect()
    }

    /// Control group of each muscle: "flexor", "extensor" or "other".
    #[getter]
    fn muscle_groups(&self) -> Vec<String> {
        self.sim
            .muscles()
            .iter()
            .map(|m| m.group.as_str().to_string())
            .collect()
    }

    /// Tendon model of each muscle, "rigid" or "compliant" (in `muscle_names` order).
    #[getter]
    fn muscle_tendons(&self) -> Vec<&'static str> {
        self.sim.muscles().iter().map(|m| m.tendon.name()).collect()
    }

    /// Gives one muscle its own tendon model mid-run, "rigid" or "compliant"; the others
    /// keep theirs (and their fibre states).
    fn set_muscle_tendon(&mut self, py: Python<'_>, name: &str, tendon: &str) -> PyResult<()> {
        let tendon = tendon.parse().or_py(py)?;
        self.sim.set_muscle_tendon(name, tendon).or_py(py)
    }

    /// The muscle model, "hill" or "spring"; settable mid-run.
    #[getter]
    fn muscle_model(&self) -> &'static str {
        self.sim.muscle_model().name()
    }

    #[setter]
    fn set_muscle_model(&mut self, py: Python<'_>, value: &str) -> PyResult<()> {
        self.sim.set_muscle_model(value.parse().or_py(py)?);
        Ok(())
    }

    /// The Hill units' tendons, "rigid" or "compliant"; settable mid-run (a compliant
    /// fibre starts in static equilibrium with its tendon). Setting it gives every muscle
    /// that tendon; reading it gives the default (see `muscle_tendons`).
    #[getter]
    fn tendon(&self) -> &'static str {
        self.sim.tendon_model().name()
    }

    #[setter]
    fn set_tendon(&mut self, py: Python<'_>, value: &str) -> PyResult<()> {
        self.sim.set_tendon_model(value.parse().or_py(py)?);
        Ok(())
    }

    /// Simulated time (s).
    #[getter]
    fn time(&self) -> f64 {
        self.sim.time()
    }

    /// Knee flexion angle (rad).
    #[getter]
    fn knee_angle(&self) -> f64 {
        self.sim.knee_angle()
    }

    /// Knee flexion velocity (rad/s).
    #[getter]
    fn knee_velocity(&self) -> f64 {
        self.sim.knee_velocity()
    }

    /// Net muscle torque about the knee (N m, positive flexing).
    #[getter]
    fn knee_torque(&self) -> f64 {
        self.sim.knee_torque()
    }

    /// Flexion limits (rad).
    #[getter]
    fn knee_limits(&self) -> (f64, f64) {
        let [a, b] = self.sim.skeleton().limits();
        (a, b)
    }

    /// Activation of every muscle.
    #[getter]
    fn activations<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(
            py,
            self.sim.muscles().iter().map(|m| m.activation).collect(),
        )
    }

    /// Tendon force of every muscle (N).
    #[getter]
    fn forces<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.sim.muscles().iter().map(|m| m.force).collect())
    }

    /// Fibre length of every muscle (m).
    #[getter]
    fn fibre_lengths<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(
            py,
            self.sim.muscles().iter().map(|m| m.fibre.length).collect(),
        )
    }

    /// Moment arm of every muscle about the knee (m, positive flexing).
    #[getter]
    fn moment_arms<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(
            py,
            self.sim.muscles().iter().map(|m| m.moment_arm).collect(),
        )
    }

    /// Vertices (float32, (N, 3), m) and triangles (uint32, (M, 3)) of a layer now:
    /// "bone", "muscle" or "skin". Muscles and skin are as the last tissue update left
    /// them, or with `carried` carried with the bones from it to now (what the viewer
    /// draws between updates).
    #[pyo3(signature = (layer, *, carried = false))]
    fn surface<'py>(
        &self,
        py: Python<'py>,
        layer: &str,
        carried: bool,
    ) -> PyResult<SurfaceArrays<'py>> {
        let layer: Layer = layer.parse().or_py(py)?;
        let sim = &self.sim;
        let surface = crate::pool::detach(py, move || {
            if carried {
                sim.carried_surface(layer)
            } else {
                sim.surface(layer)
            }
        });
        Ok((
            vec3_array(py, &surface.vertices),
            tri_array(py, &surface.triangles),
        ))
    }

    /// Area change A/A0 − 1 of each fat element's outer face (float32; empty without tissue).
    #[getter]
    fn area_change<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f32>> {
        metric_array(py, &self.sim, |m| &m.area_change)
    }

    /// Deformation degree (paper Eq. 5, m) of each fat element (float32; empty without tissue).
    #[getter]
    fn deformation_degree<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f32>> {
        metric_array(py, &self.sim, |m| &m.deformation_degree)
    }

    /// Volume over rest volume of each fat element (float32; empty without tissue).
    #[getter]
    fn volume_ratio<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f32>> {
        metric_array(py, &self.sim, |m| &m.volume_ratio)
    }

    /// Volume over rest volume of each muscle (float32; empty without tissue).
    #[getter]
    fn muscle_volume_ratio<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f32>> {
        metric_array(py, &self.sim, |m| &m.muscle_volume_ratio)
    }

    /// Fat elements with a folded corner now (a corner Jacobian at or below zero,
    /// ParaView's test of a valid hexahedron); 0 without tissue.
    #[getter]
    fn folded_elements(&self, py: Python<'_>) -> usize {
        let sim = &self.sim;
        crate::pool::detach(py, || sim.tissue_metrics().map_or(0, |m| m.inverted))
    }

    /// What the build could not take from the muscle catalogue: one line per muscle
    /// whose parameters came from its volume and length (also issued as Python
    /// warnings by `from_file` and `from_nifti`).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.sim.warnings().to_vec()
    }

    /// How often the tissue's validity guard stepped in since the build: a dict of
    /// `updates` (tissue updates it moved fat in) and `vertices` (fat vertices it moved,
    /// summed); zeros without tissue. Part of a checkpoint.
    #[getter]
    fn guard_tally<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let t = self
            .sim
            .tissue()
            .map(|t| t.guard_tally())
            .unwrap_or_default();
        let d = PyDict::new(py);
        d.set_item("updates", t.updates)?;
        d.set_item("vertices", t.vertices)?;
        Ok(d)
    }

    /// Every soundness check of the tissue now (folded and squashed fat, muscles and
    /// bones out through the skin, muscles in bone and in one another, skin crossings,
    /// muscle volumes, the fat's distance from rest): a dict shaped as `summary.json`'s
    /// audit, None without tissue. Exact, about a second on a whole leg.
    fn audit<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        let sim = &self.sim;
        let Some(a) = crate::pool::detach(py, || sim.audit()) else {
            return Ok(None);
        };
        let json = serde_json::to_string(&a)
            .map_err(|e| py_err(py, Kind::Simulation, format!("audit: {e}")))?;
        py.import("json")?.call_method1("loads", (json,)).map(Some)
    }

    /// How far each muscle's surface reaches into bone now: a dict of per-muscle arrays
    /// `vertices_over_1mm` (int64) and `deepest_m` (float32), empty without tissue.
    fn muscles_in_bone<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let sim = &self.sim;
        let o = crate::pool::detach(py, || sim.muscles_in_bone()).unwrap_or_default();
        let (count, deepest) = o.iter().map(|b| (b.vertices_over_1mm, b.deepest_m)).unzip();
        reach_dict(py, count, ("deepest_m", deepest))
    }

    /// How far each muscle's surface reaches out through the skin now: a dict of
    /// per-muscle arrays `vertices_over_1mm` (int64) and `farthest_m` (float32), empty
    /// without tissue (or where the skin cannot be closed into a mesh).
    fn muscles_outside_skin<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let sim = &self.sim;
        breach_dict(py, crate::pool::detach(py, || sim.muscles_outside_skin()))
    }

    /// How far each bone's surface reaches out through the skin now, as
    /// `muscles_outside_skin` but per bone, in `bone_names` order.
    fn bones_outside_skin<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let sim = &self.sim;
        breach_dict(py, crate::pool::detach(py, || sim.bones_outside_skin()))
    }

    /// Bone names, in the order of `bones_outside_skin`.
    #[getter]
    fn bone_names(&self) -> Vec<String> {
        self.sim
            .lattice()
            .bones
            .iter()
            .map(|b| b.name.clone())
            .collect()
    }

    /// Number of fat elements (hexahedra).
    #[getter]
    fn n_fat_elements(&self) -> usize {
        self.sim.lattice().fat.hexes.len()
    }

    /// Puts the knee at `angle` (rad) with flexion `velocity` (rad/s).
    #[pyo3(signature = (angle, velocity = 0.0))]
    fn set_knee(&mut self, py: Python<'_>, angle: f64, velocity: f64) -> PyResult<()> {
        let sim = &mut self.sim;
        crate::pool::detach(py, move || sim.set_knee(angle, velocity)).or_py(py)
    }

    /// A checkpoint of the whole dynamic state, the muscle and tendon models included.
    fn state(&self) -> PyState {
        PyState {
            inner: self.sim.state(),
        }
    }

    /// Restores a checkpoint of this simulation.
    fn set_state(&mut self, py: Python<'_>, state: &PyState) -> PyResult<()> {
        let (sim, inner) = (&mut self.sim, &state.inner);
        crate::pool::detach(py, move || sim.set_state(inner)).or_py(py)
    }

    /// Renders the leg off-screen: uint8 (height, width, 3).
    #[pyo3(signature = (width = 640, height = 480, *, color = "area", camera = "oblique"))]
    fn render<'py>(
        &mut self,
        py: Python<'py>,
        width: u32,
        height: u32,
        color: &str,
        camera: &str,
    ) -> PyResult<Bound<'py, PyArray3<u8>>> {
        render::render(
            py,
            &self.sim,
            &mut self.offscreen,
            width,
            height,
            color,
            camera,
        )
    }

    fn __repr__(&self) -> String {
        format!(
            "Simulation(t={:.4} s, knee={:.1} deg, {} muscles, {} fat elements)",
            self.sim.time(),
            self.sim.knee_angle().to_degrees(),
            self.sim.muscles().len(),
            self.sim.lattice().fat.hexes.len()
        )
    }
}

/// The compiled core of the `myoslice` package.
#[pymodule]
mod _myoslice {
    #[pymodule_export]
    use super::scenario_run::{check_scenario, run_scenario};
    #[pymodule_export]
    use super::{PySimulation, PyState};

    #[pymodule_init]
    fn init(m: &pyo3::Bound<'_, pyo3::types::PyModule>) -> pyo3::PyResult<()> {
        use pyo3::types::PyModuleMethods;
        super::pool::note_origin();
        m.add("__version__", env!("CARGO_PKG_VERSION"))
    }
}
