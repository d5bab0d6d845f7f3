//! The muscle catalogue: Hill parameters and groups per muscle name (`assets/muscles.toml`).

use std::collections::BTreeMap;
use std::path::Path;

use serde::Deserialize;

use super::TendonModel;
use crate::error::{Error, Result};

/// The embedded catalogue.
pub const DEFAULT_CATALOGUE: &str = include_str!("../../../../assets/muscles.toml");

/// Which control group a muscle belongs to (slider groups and presets).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MuscleGroup {
    /// Knee flexors (hamstrings, gracilis, sartorius, gastrocnemii, ...).
    Flexor,
    /// Knee extensors (the quadriceps).
    Extensor,
    /// Everything else.
    Other,
}

impl MuscleGroup {
    /// Lower-case name.
    pub fn as_str(self) -> &'static str {
        match self {
            MuscleGroup::Flexor => "flexor",
            MuscleGroup::Extensor => "extensor",
            MuscleGroup::Other => "other",
        }
    }
}

/// One catalogue entry; missing numbers fall back to the default rule.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CatalogueEntry {
    /// Maximum isometric force (N).
    pub max_isometric_force_n: Option<f64>,
    /// Optimal fibre length (m).
    pub optimal_fibre_length_m: Option<f64>,
    /// Tendon slack length (m).
    pub tendon_slack_length_m: Option<f64>,
    /// Pennation at optimal length (degrees).
    pub pennation_deg: Option<f64>,
    /// Maximum contraction velocity (optimal lengths per second).
    pub max_contraction_velocity: Option<f64>,
    /// Control group.
    pub group: Option<MuscleGroup>,
    /// Origin bone, overriding the label table.
    pub origin: Option<String>,
    /// Insertion bone, overriding the label table.
    pub insertion: Option<String>,
    /// Where on the origin bone the muscle attaches: `nearest` (default: the nearest
    /// surface point to the muscle's end), `superior` or `inferior` (its extreme point).
    pub origin_site: Option<String>,
    /// Where on the insertion bone it attaches (as `origin_site`).
    pub insertion_site: Option<String>,
    /// The insertion lies at least this far (m) below the knee axis: the nearest point of
    /// the insertion bone to the muscle's end among those that low (hamstring and pes
    /// anserinus tendons insert below the joint line, not on the plateau's rim).
    pub insertion_below_knee_m: Option<f64>,
    /// The origin lies at least this far (m) above the knee axis: the nearest point of the
    /// origin bone to the muscle's end among those that high (the gastrocnemius heads
    /// arise above the condyles' articular surfaces, not level with the flexion axis).
    pub origin_above_knee_m: Option<f64>,
    /// Normalised fibre length at the rest pose (default from `[default]`).
    pub rest_fibre_length: Option<f64>,
    /// This muscle's tendon model (`"rigid"` or `"compliant"`), whatever the simulation's
    /// default (`SimulationConfig::tendon`); e.g. compliant only where the tendon is long
    /// against the fibre, as for the triceps surae.
    pub tendon: Option<TendonModel>,
    /// A via point on the origin's body this far (m) above the insertion at rest: the
    /// quadriceps tendon runs down the trochlear groove onto the patella.
    pub via_above_insertion_m: Option<f64>,
    /// Radius (m) of the cylinder about the knee axis the tendon wraps over; by default
    /// the tendon's distance from the axis at rest.
    pub wrap_radius_m: Option<f64>,
    /// Provenance.
    pub source: Option<String>,
}

/// The rule for muscles the catalogue lacks.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DefaultRule {
    /// Force per physiological cross-section (Pa).
    pub specific_tension_pa: f64,
    /// Optimal fibre length as a fraction of the rest path length.
    pub fibre_fraction: f64,
    /// Pennation (degrees).
    pub pennation_deg: f64,
    /// Maximum contraction velocity.
    pub max_contraction_velocity: f64,
    /// Normalised fibre length at the rest pose.
    pub rest_fibre_length: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCatalogue {
    default: DefaultRule,
    #[serde(default)]
    muscle: BTreeMap<String, CatalogueEntry>,
}

/// Muscle parameters by name.
#[derive(Debug, Clone, PartialEq)]
pub struct MuscleCatalogue {
    /// The default rule.
    pub default: DefaultRule,
    /// Entries by muscle name.
    pub muscles: BTreeMap<String, CatalogueEntry>,
}

/// Parameters resolved for one muscle of a model.
#[derive(Debug, Clone, PartialEq)]
pub struct ResolvedMuscle {
    /// Maximum isometric force (N).
    pub max_isometric_force: f64,
    /// Optimal fibre length before scaling to the model (m).
    pub optimal_fibre_length: f64,
    /// Tendon slack length before scaling (m).
    pub tendon_slack_length: f64,
    /// Pennation (rad).
    pub pennation: f64,
    /// Maximum contraction velocity.
    pub max_contraction_velocity: f64,
    /// Group.
    pub group: MuscleGroup,
    /// Whether the catalogue had an entry (else the default rule made it).
    pub from_catalogue: bool,
    /// Normalised fibre length at the rest pose.
    pub rest_fibre_length: f64,
}

impl Default for MuscleCatalogue {
    fn default() -> Self {
        // The embedded file is checked by a test; fall back to an empty catalogue rather
        // than panic if it were ever broken.
        Self::from_toml_str(DEFAULT_CATALOGUE, "assets/muscles.toml").unwrap_or(Self {
            default: DefaultRule {
                specific_tension_pa: 6e5,
                fibre_fraction: 0.5,
                pennation_deg: 0.0,
                max_contraction_velocity: 10.0,
                rest_fibre_length: 1.0,
            },
            muscles: BTreeMap::new(),
        })
    }
}

impl MuscleCatalogue {
    /// Parses a catalogue; `origin` names it in errors.
    pub fn from_toml_str(text: &str, origin: &str) -> Result<Self> {
        let raw: RawCatalogue = toml::from_str(text).map_err(|e| Error::Parse {
            path: origin.into(),
            reason: e.to_string(),
        })?;
        let cat = Self {
            default: raw.default,
            muscles: raw.muscle,
        };
        for (name, e) in &cat.muscles {
            for (key, v) in [
                ("max_isometric_force_n", e.max_isometric_force_n),
                ("optimal_fibre_length_m", e.optimal_fibre_length_m),
                ("tendon_slack_length_m", e.tendon_slack_length_m),
                ("max_contraction_velocity", e.max_contraction_velocity),
                ("wrap_radius_m", e.wrap_radius_m),
                ("insertion_below_knee_m", e.insertion_below_knee_m),
                ("origin_above_knee_m", e.origin_above_knee_m),
                ("via_above_insertion_m", e.via_above_insertion_m),
                ("rest_fibre_length", e.rest_fibre_length),
            ] {
                if let Some(v) = v
                    && !(v.is_finite() && v > 0.0)
                {
                    return Err(Error::Parse {
                        path: origin.into(),
                        reason: format!("muscle.{name}.{key} = {v}: expected a finite value > 0"),
                    });
                }
            }
        }
        for (name, e) in &cat.muscles {
            // The pes anserinus is an insertion site only.
            const SITES: [&str; 4] = ["nearest", "superior", "inferior", "anteromedial"];
            for (key, v, allowed) in [
                ("origin_site", &e.origin_site, &SITES[..3]),
                ("insertion_site", &e.insertion_site, &SITES[..]),
            ] {
                if let Some(v) = v
                    && !allowed.contains(&v.as_str())
                {
                    return Err(Error::Parse {
                        path: origin.into(),
                        reason: format!(
                            "muscle.{name}.{key} = '{v}': expected {}",
                            allowed.join(", ")
                        ),
                    });
                }
            }
        }
        Ok(cat)
    }

    /// Reads a catalogue file.
    pub fn from_path(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Self::from_toml_str(&text, &path.display().to_string())
    }

    /// Parameters for a muscle of volume `volume_m3` and rest path length `path_m`.
    pub fn resolve(&self, name: &str, volume_m3: f64, path_m: f64) -> ResolvedMuscle {
        let e = self.muscles.get(name);
        let d = &self.default;
        let lopt = e
            .and_then(|e| e.optimal_fibre_length_m)
            .unwrap_or(d.fibre_fraction * path_m);
        let lts = e
            .and_then(|e| e.tendon_slack_length_m)
            .unwrap_or(((1.0 - d.fibre_fraction) * path_m).max(1e-3));
        let fmax = e
            .and_then(|e| e.max_isometric_force_n)
            .unwrap_or(d.specific_tension_pa * volume_m3 / lopt.max(1e-3));
        ResolvedMuscle {
            max_isometric_force: fmax,
            optimal_fibre_length: lopt,
            tendon_slack_length: lts,
            pennation: e
                .and_then(|e| e.pennation_deg)
                .unwrap_or(d.pennation_deg)
                .to_radians(),
            max_contraction_velocity: e
                .and_then(|e| e.max_contraction_velocity)
                .unwrap_or(d.max_contraction_velocity),
            group: e.and_then(|e| e.group).unwrap_or(MuscleGroup::Other),
            from_catalogue: e.is_some_and(|e| e.max_isometric_force_n.is_some()),
            rest_fibre_length: e
                .and_then(|e| e.rest_fibre_length)
                .unwrap_or(d.rest_fibre_length),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_embedded_catalogue_parses_and_has_the_knee_muscles() {
        let c = MuscleCatalogue::from_toml_str(DEFAULT_CATALOGUE, "embedded").unwrap();
        let st = c.resolve("semitendinosus", 1e-4, 0.4);
        assert!(st.from_catalogue && (st.max_isometric_force - 410.0).abs() < 1e-9);
        assert_eq!(st.group, MuscleGroup::Flexor);
        assert_eq!(
            c.resolve("vastus_lateralis", 1e-4, 0.3).group,
            MuscleGroup::Extensor
        );
        let pop = c.resolve("popliteus", 12e-6, 0.06);
        assert!(
            !pop.from_catalogue
                && pop.max_isometric_force > 50.0
                && pop.max_isometric_force < 1000.0
        );
    }

    #[test]
    fn bad_catalogue_values_are_named() {
        let t = "[default]\nspecific_tension_pa = 1\nfibre_fraction = 0.5\npennation_deg = 0\nmax_contraction_velocity = 10\nrest_fibre_length = 1\n[muscle.x]\nmax_isometric_force_n = -3\n";
        let e = MuscleCatalogue::from_toml_str(t, "c.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("muscle.x.max_isometric_force_n"), "{e}");
        let t = "[default]\nspecific_tension_pa = 1\nfibre_fraction = 0.5\npennation_deg = 0\nmax_contraction_velocity = 10\nrest_fibre_length = 1\n[muscle.x]\nforce = 3\n";
        let e = MuscleCatalogue::from_toml_str(t, "c.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("force"), "{e}");
    }

    #[test]
    fn the_pes_anserinus_is_an_insertion_site_only() {
        let head = "[default]\nspecific_tension_pa = 1\nfibre_fraction = 0.5\npennation_deg = 0\nmax_contraction_velocity = 10\nrest_fibre_length = 1\n[muscle.x]\n";
        let ok = format!("{head}insertion_site = \"anteromedial\"\n");
        assert!(MuscleCatalogue::from_toml_str(&ok, "c.toml").is_ok());
        let bad = format!("{head}origin_site = \"anteromedial\"\n");
        let e = MuscleCatalogue::from_toml_str(&bad, "c.toml")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("muscle.x.origin_site = 'anteromedial'") && !e.contains(", anteromedial"),
            "{e}"
        );
    }
}
