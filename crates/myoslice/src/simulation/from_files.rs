//! Simulations of the phantom and of the user's own label volumes.

use super::{Simulation, SimulationConfig};
use crate::error::Result;
use crate::lattice::{BuildOptions, Lattice};
use crate::muscle::MuscleCatalogue;

impl Simulation {
    /// The built-in phantom with the default lattice options and muscle catalogue.
    pub fn phantom(config: SimulationConfig) -> Result<Self> {
        let (volume, table) = crate::phantom::Phantom::default().generate()?;
        let lattice = Lattice::build(&volume, &table, &BuildOptions::default())?;
        Self::new(lattice, config, &MuscleCatalogue::default())
    }

    /// A label volume (NIfTI-1/-2 or NRRD) and its label table or a tool's label list
    /// (unknown names are an error).
    pub fn from_nifti(
        volume: impl AsRef<std::path::Path>,
        labels: impl AsRef<std::path::Path>,
        build: &BuildOptions,
        config: SimulationConfig,
    ) -> Result<Self> {
        Self::from_segmentation(
            volume,
            Some(labels.as_ref()),
            crate::label_names::Unmapped::Error,
            build,
            config,
        )
    }

    /// A label volume (NIfTI-1/-2 or NRRD) with the meaning of its labels: a label table or
    /// a tool's label list at `labels`, or, when None, the segment names of a 3D Slicer
    /// segmentation (see [`crate::io::read_segmentation`]).
    pub fn from_segmentation(
        volume: impl AsRef<std::path::Path>,
        labels: Option<&std::path::Path>,
        mapping: impl Into<crate::label_mapping::LabelMapping>,
        build: &BuildOptions,
        config: SimulationConfig,
    ) -> Result<Self> {
        let (v, t) = crate::io::read_segmentation(volume, labels, mapping)?;
        let lattice = Lattice::build(&v, &t, build)?;
        Self::new(lattice, config, &MuscleCatalogue::default())
    }

    /// Any label volume or PNG stack myoslice reads, told apart by content
    /// ([`crate::io::read_input`]).
    ///
    /// ```no_run
    /// use myoslice::prelude::*;
    /// let sim = Simulation::from_file(
    ///     "leg.seg.nrrd",
    ///     None,
    ///     Unmapped::Error,
    ///     &BuildOptions::default(),
    ///     SimulationConfig::default(),
    /// )?;
    /// # Ok::<(), myoslice::Error>(())
    /// ```
    pub fn from_file(
        path: impl AsRef<std::path::Path>,
        labels: Option<&std::path::Path>,
        mapping: impl Into<crate::label_mapping::LabelMapping>,
        build: &BuildOptions,
        config: SimulationConfig,
    ) -> Result<Self> {
        let (v, t) = crate::io::read_input(path, labels, mapping)?;
        let lattice = Lattice::build(&v, &t, build)?;
        Self::new(lattice, config, &MuscleCatalogue::default())
    }

    /// What the user should know about how this model was built: each muscle the
    /// catalogue has no entry for, whose parameters came from its volume and length
    /// (optimal fibre length = `fibre_fraction` of its rest path, tendon slack length the
    /// rest, force = specific tension × volume / fibre length: `[default]` in
    /// `assets/muscles.toml`). In muscle order; none for the phantom and the Visible
    /// Human leg, whose muscles all have entries.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }
}
