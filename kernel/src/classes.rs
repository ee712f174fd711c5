//! The class names the shell itself must name: everything else is named by
//! the scene. Each is an ordinary plugin on the plugin path, replaceable by a
//! library of the same name.

/// The class the shell wraps every transformed instance in. It must offer the
/// `FromTransform` capability: the shell hands it the composed, checked
/// matrix as typed data.
pub const INSTANCE_TRANSFORM: &str = "transform";

/// The integrator a scene gets when `[render]` names none.
pub const DEFAULT_INTEGRATOR: &str = "whitted";
