//! No code: a dependency of every front whose only job is to make the features of shared
//! dependencies the same in each of the workspace's builds, so that the CLI, the viewer
//! and the Python wheel run one build of the core (the technique of `cargo hakari`).
