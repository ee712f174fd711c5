//! The class names the shell itself must name: everything else is named by
//! the scene. Each is an ordinary plugin on the plugin path, replaceable by a
//! library of the same name.

/// The class the shell wraps every transformed instance in. It must offer the
/// `FromTransform` capability: the shell hands it the composed, checked
/// matrix as typed data.
pub const INSTANCE_TRANSFORM: &str = "transform";

/// The aggregate the shell builds over an object that offers the
/// primitive-set protocol (a mesh) where no aggregate flattens it, unless
/// the object's `accel` key names another class (or `"none"`).
pub const DEFAULT_ACCEL: &str = "bvh";

/// The light class the shell makes for every emitting instance (an
/// instance bound to a shader whose `lobes` has emission). It must offer the
/// `Area` capability: the shell binds the instance to it.
pub const AREA_LIGHT: &str = "area";

/// The integrator a scene gets when `[render]` names none.
pub const DEFAULT_INTEGRATOR: &str = "whitted";

/// Classes whose own parameters place their child in the renderer's space
/// (they subtract `[render] origin` in f64 themselves): the shell creates
/// their children unshifted, as below any instance transform.
pub const PLACE_THEIR_CHILD: [&str; 2] = [INSTANCE_TRANSFORM, "motion"];

/// Not a plugin: a macro group, which the shell expands. A definition of
/// this class takes only `children`; every instance of it splices those
/// children into its parent, each transform composed with the instance's
/// and the instance's shader bound where a child binds none. The parent's
/// aggregate then builds over the members directly: a group costs no
/// level, no object and no query.
pub const GROUP: &str = "group";
