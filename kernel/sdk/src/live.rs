//! Live handles: a plugin object and its class's record, with one safe
//! method per entry (generated from the declarations in
//! `rtk_abi::entries`). Their constructors are `unsafe`: whoever makes one
//! vouches that the object outlives it. Both sides use them — an
//! aggregate's [`Child`](crate::Child) and a shader's
//! [`Material`](crate::Material) on the plugin side, `rtk-handles` on the
//! host side — so each entry has exactly one calling code.
//!
//! A handle is neither `Clone` nor `Copy`, and the wrappers that hold one
//! lend it out only by shared reference: nobody but its owner can reach its
//! `&mut self` entries (`add_child`, `prepare`), which need the object to
//! themselves.

use rtk_abi::*;
use std::ffi::c_void;

macro_rules! live {
    ($(#[$doc:meta])* $name:ident, $class:ident) => {
        $(#[$doc])*
        pub struct $name {
            this: *mut c_void,
            class: $class,
        }

        // SAFETY: the object is immutable after `prepare` (the entries that
        // change it take `&mut self`) and its class is `Send + Sync` by the
        // SDK's contract (`Plugin: Send + Sync`); the record is a `'static`
        // table in a library that is never unloaded.
        unsafe impl Send for $name {}
        // SAFETY: as for `Send`: shared use only reaches `&self` entries,
        // which the SDK's traits require to be safe to call concurrently.
        unsafe impl Sync for $name {}

        impl $name {
            /// A handle on `this`, an object of `class`.
            ///
            /// # Safety
            /// `this` must be a live object made by `class`'s plugin and
            /// stay alive, at the same address, for as long as the handle
            /// exists; whoever holds the handle mutably must have the object
            /// to itself.
            #[doc(hidden)]
            pub unsafe fn new(this: *mut c_void, class: $class) -> Self {
                Self { this, class }
            }

            /// The class's record.
            #[inline(always)]
            pub fn raw_class(&self) -> $class {
                self.class
            }

            /// The object's opaque pointer (to pass back to its record).
            #[inline(always)]
            pub fn raw_this(&self) -> *mut c_void {
                self.this
            }
        }

        impl std::fmt::Debug for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.debug_struct(stringify!($name)).field("class", &self.class_name()).finish()
            }
        }
    };
}

live!(
    /// An object of any class (primitive, aggregate, transform, CSG).
    LiveObject,
    ObjectModuleRef
);
live!(
    /// A shader.
    LiveShader,
    ShaderModuleRef
);
live!(
    /// An integrator.
    LiveIntegrator,
    IntegratorModuleRef
);
live!(
    /// A camera.
    LiveCamera,
    CameraModuleRef
);
live!(
    /// A light.
    LiveLight,
    LightModuleRef
);

macro_rules! class_name {
    ($($name:ident),*) => {$(
        impl $name {
            /// The class name its plugin declared.
            pub fn class_name(&self) -> &'static str {
                self.class.meta().class_name.as_str()
            }
        }
    )*};
}
class_name!(
    LiveObject,
    LiveShader,
    LiveIntegrator,
    LiveCamera,
    LiveLight
);

/// The host's scene services as a plugin calls them. Laid out as
/// [`SceneRef`] (context, record), so a `&SceneRef` can be lent as one.
#[repr(C)]
pub struct LiveServices {
    this: *mut c_void,
    class: SceneServicesRef,
}

// SAFETY: the host's services are safe to call from any thread (the host's
// `Services: Sync`); the record is `'static`.
unsafe impl Send for LiveServices {}
// SAFETY: as for `Send`.
unsafe impl Sync for LiveServices {}

impl LiveServices {
    /// The class name used in a failure message: the host.
    pub fn class_name(&self) -> &'static str {
        "rtk (host)"
    }
    /// The record.
    #[inline(always)]
    pub fn raw_class(&self) -> SceneServicesRef {
        self.class
    }
    /// The host's context.
    #[inline(always)]
    pub fn raw_this(&self) -> *mut c_void {
        self.this
    }
}

rtk_abi::object_entries!(crate::__callers, LiveObject);
rtk_abi::shader_entries!(crate::__callers, LiveShader);
rtk_abi::integrator_entries!(crate::__callers, LiveIntegrator);
rtk_abi::camera_entries!(crate::__callers, LiveCamera);
rtk_abi::light_entries!(crate::__callers, LiveLight);
rtk_abi::scene_entries!(crate::__callers, LiveServices);
