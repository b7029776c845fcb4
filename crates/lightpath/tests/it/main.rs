//! Lightpath's integration tests, one module per subject, in one test binary: fifteen
//! binaries took most of `cargo test --workspace`'s time to compile and link (issue 25's
//! quick start). Run one subject with `cargo test -p lightpath --test it <module>::`.

mod common;

mod cli;
mod connect;
mod denoise;
mod docs;
mod embree;
mod farm;
mod glints;
mod gltf;
mod guiding;
mod hostile;
mod identity;
mod media;
mod meshes;
mod mutation;
mod newcomer;
mod openpbr;
mod peer;
mod presence;
mod render;
mod sampling;
mod settings;
mod style;
mod subsurface;
mod usd;
mod view;
mod workflow;
