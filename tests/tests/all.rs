//! rtk's integration tests, one binary (ripgrep's layout): each module a topic.

mod aggregates;
mod bad_scenes;
mod dropin;
mod hostile;
mod hygiene;
mod loading;
mod panics;
mod quadrics;
mod refusals;
mod shading;
mod silhouette;
mod stress;
mod trace;
mod whitted;
