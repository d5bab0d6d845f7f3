//! Nothing to build: present so that the host-side features in `[build-dependencies]`
//! take part in the build (see Cargo.toml).

fn main() {}
