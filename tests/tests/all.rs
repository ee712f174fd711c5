//! rtk's integration tests, one binary (ripgrep's layout): each module a topic.

mod aggregates;
mod authoring;
mod bad_scenes;
mod csg;
mod distributed;
mod dropin;
mod farm;
mod hostile;
mod hygiene;
mod interior;
mod loading;
mod long_renders;
mod materials;
mod motion;
mod objects;
mod panics;
mod path;
mod quadrics;
mod refusals;
mod shading;
mod silhouette;
mod soundness;
mod stress;
mod thinlens;
mod trace;
mod whitted;
