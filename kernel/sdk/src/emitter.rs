//! What an area light is bound to: an emitting instance, as counted
//! handles a light may keep for its whole life.

use crate::{Child, LiveShader};
use rtk_abi::*;

/// A shader held by a plugin for as long as it likes (an area light keeps
/// its emitter's): a counted handle with the shader's entries as safe
/// methods ([`LiveShader`], which it dereferences to).
pub struct ShaderHandle {
    live: LiveShader,
    lobes: u32,
    keep: KeepAlive,
}

impl ShaderHandle {
    /// Take over a shader record with one count on it.
    ///
    /// # Safety
    /// `r` must be a live shader and `keep` hold one count on it that the
    /// handle now owns.
    pub(crate) unsafe fn from_counted(r: ShaderRef, keep: KeepAlive) -> Self {
        ShaderHandle {
            // SAFETY: the count keeps the shader alive while the handle lives.
            live: unsafe { LiveShader::new(r.this as *mut _, r.class) },
            lobes: r.lobes,
            keep,
        }
    }

    /// The [`lobe`] kinds the shader reported when it was created.
    pub fn lobes(&self) -> u32 {
        self.lobes
    }
}

impl std::ops::Deref for ShaderHandle {
    type Target = LiveShader;
    #[inline(always)]
    fn deref(&self) -> &LiveShader {
        &self.live
    }
}

impl Drop for ShaderHandle {
    fn drop(&mut self) {
        // SAFETY: the handle owns one count, released once.
        unsafe { (self.keep.release)(self.keep.owner) };
    }
}

// SAFETY: shaders are immutable after creation and `Send + Sync` by the
// SDK's contract; the count is released with a thread-safe call.
unsafe impl Send for ShaderHandle {}
// SAFETY: as for `Send`.
unsafe impl Sync for ShaderHandle {}

/// An emitting instance as an area light holds it (`Area::bind_emitter`):
/// the object (counted, with its instance bindings, which name the light),
/// its placement in the renderer's space, and the emitting shader (counted).
pub struct Emitter {
    /// The emitting object; sample it through its `sample_surface` (or its
    /// triangles, through [`Child::prim_set`]) and place what it gives with
    /// `to_world`.
    pub object: Child,
    /// Object to world (renderer's space), composed in f64 by the shell.
    pub to_world: glam::DAffine3,
    /// The shader whose `emitted` radiance the surface sends.
    pub shader: ShaderHandle,
}

impl Emitter {
    /// Take over what the host passed to `bind_emitter`.
    ///
    /// # Safety
    /// The record's contract: `r.object` as for `add_child`, and `r.shader`
    /// a live shader with one count in `r.shader_keep` that is now ours.
    pub(crate) unsafe fn from_counted(r: EmitterRef) -> Self {
        Emitter {
            // SAFETY: guaranteed by the caller.
            object: unsafe { Child::from_counted(r.object) },
            to_world: r.to_world.to_daffine(),
            // SAFETY: guaranteed by the caller.
            shader: unsafe { ShaderHandle::from_counted(r.shader, r.shader_keep) },
        }
    }
}

impl std::fmt::Debug for Emitter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Emitter")
            .field("object", &self.object)
            .field("shader", &self.shader.class_name())
            .finish()
    }
}
