//! The one error type of the core crate.

use std::path::PathBuf;

/// Everything that can go wrong in myoslice, each variant naming what was wrong.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file could not be opened or read.
    #[error("cannot read {path}: {source}")]
    Io {
        /// The file that failed.
        path: PathBuf,
        /// The operating-system error.
        #[source]
        source: std::io::Error,
    },
    /// A file could not be written.
    #[error("cannot write {path}: {source}")]
    Write {
        /// The file that failed.
        path: PathBuf,
        /// The operating-system error.
        #[source]
        source: std::io::Error,
    },
    /// A NIfTI file is malformed or uses something we do not read.
    #[error("NIfTI {path}: {reason}")]
    Nifti {
        /// The offending file.
        path: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
    /// A PNG slice or PNG stack is malformed.
    #[error("PNG {path}: {reason}")]
    Png {
        /// The offending file or folder.
        path: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
    /// A label table, manifest, catalogue or scenario could not be parsed.
    #[error("{path}: {reason}")]
    Parse {
        /// The offending file (or a description of the in-memory source).
        path: PathBuf,
        /// The parser's message, naming the key and line where it can.
        reason: String,
    },
    /// The volume holds a label id that the label table does not define.
    #[error(
        "label {id} occurs in the volume ({voxels} voxels) but is missing from the label table"
    )]
    UnknownLabel {
        /// The undefined id.
        id: u32,
        /// How many voxels carry it.
        voxels: u64,
    },
    /// A structure or muscle name was not found.
    #[error("unknown {what} '{name}'{hint}")]
    UnknownName {
        /// What kind of thing was looked up ("muscle", "bone", "group").
        what: &'static str,
        /// The name given.
        name: String,
        /// A suggestion such as " (did you mean 'semitendinosus'?)".
        hint: String,
    },
    /// A numeric option or input is outside its valid range (or NaN).
    #[error("invalid {name} = {value}: {expected}")]
    InvalidValue {
        /// The option or input name.
        name: String,
        /// The value given, printed.
        value: String,
        /// What was expected.
        expected: String,
    },
    /// The input has no content we can build from.
    #[error("cannot build a lattice: {0}")]
    Build(String),
    /// The simulation state stopped being finite; the last good state is kept.
    #[error(
        "simulation became non-finite at t = {time:.4} s ({what}); the last good state was kept"
    )]
    NonFinite {
        /// Simulated time of the failed step.
        time: f64,
        /// Which quantity went non-finite.
        what: String,
    },
    /// A saved state does not fit this simulation.
    #[error("state does not match this simulation: {0}")]
    StateMismatch(String),
}

/// Result alias for the core crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }

    /// A [`Error::Parse`] of the source `path` (a file, or a description of the text).
    pub(crate) fn parse(path: impl Into<PathBuf>, reason: impl Into<String>) -> Self {
        Error::Parse {
            path: path.into(),
            reason: reason.into(),
        }
    }

    pub(crate) fn write(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Write {
            path: path.into(),
            source,
        }
    }

    pub(crate) fn invalid(
        name: impl Into<String>,
        value: impl std::fmt::Display,
        expected: impl Into<String>,
    ) -> Self {
        Error::InvalidValue {
            name: name.into(),
            value: value.to_string(),
            expected: expected.into(),
        }
    }

    /// An unknown-name error with a "did you mean" hint drawn from `known`.
    pub(crate) fn unknown_name<'a>(
        what: &'static str,
        name: &str,
        known: impl IntoIterator<Item = &'a str>,
    ) -> Self {
        let best = known
            .into_iter()
            .map(|k| (edit_distance(name, k), k))
            .min_by_key(|(d, _)| *d);
        let hint = match best {
            Some((d, k)) if d <= name.len().max(3) / 2 + 1 => format!(" (did you mean '{k}'?)"),
            _ => String::new(),
        };
        Error::UnknownName {
            what,
            name: name.to_string(),
            hint,
        }
    }
}

/// Checks that `v` is finite and within `[lo, hi]`.
#[allow(dead_code)] // used by the simulation front
pub(crate) fn check_range(name: &str, v: f64, lo: f64, hi: f64) -> Result<f64> {
    if v.is_finite() && v >= lo && v <= hi {
        Ok(v)
    } else {
        Err(Error::invalid(
            name,
            v,
            format!("expected a finite value in [{lo}, {hi}]"),
        ))
    }
}

/// Checks that `v` is finite and strictly positive.
#[allow(dead_code)] // used by the simulation front
pub(crate) fn check_positive(name: &str, v: f64) -> Result<f64> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(Error::invalid(name, v, "expected a finite value > 0"))
    }
}

fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            let cost = usize::from(ca != *cb);
            cur[j + 1] = (prev[j] + cost).min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

/// The choice named `s` among `all`, or an error naming the option and the choices.
pub(crate) fn parse_choice<T: Copy>(
    option: &str,
    s: &str,
    all: &[T],
    name: fn(T) -> &'static str,
) -> Result<T> {
    all.iter().copied().find(|&c| name(c) == s).ok_or_else(|| {
        let names: Vec<String> = all.iter().map(|&c| format!("'{}'", name(c))).collect();
        Error::invalid(
            option,
            format!("'{s}'"),
            format!("expected {}", names.join(" or ")),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_name_suggests_the_closest_known_name() {
        let e = Error::unknown_name("muscle", "semitendinosis", ["sartorius", "semitendinosus"]);
        assert!(
            e.to_string().contains("did you mean 'semitendinosus'"),
            "{e}"
        );
        let e = Error::unknown_name("muscle", "xyz", ["sartorius"]);
        assert!(!e.to_string().contains("did you mean"), "{e}");
    }

    #[test]
    fn range_checks_reject_nan_and_out_of_range() {
        assert!(check_range("e", f64::NAN, 0.0, 1.0).is_err());
        assert!(check_range("e", 1.5, 0.0, 1.0).is_err());
        assert!(check_range("e", 0.5, 0.0, 1.0).is_ok());
        assert!(check_positive("dt", 0.0).is_err());
        assert!(check_positive("dt", -1.0).is_err());
    }
}
