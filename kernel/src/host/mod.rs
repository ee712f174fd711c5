//! The host side of the boundary: owned, safe handles to what plugins create,
//! and the host-services trait from which the scene record is built.
//!
//! The shell and the host never call a record entry themselves: they hold
//! [`ObjectBuilder`]s and [`Object`]s, [`Shader`]s, [`Light`]s, [`Camera`]s and
//! [`Integrator`]s, each of which destroys its plugin object on `Drop` and
//! offers the entries as safe methods. The host implements [`Services`] (the
//! kernel's `Trace`, the root's queries, lights, materials); a generic shim
//! turns it into the [`SceneRef`](crate::abi::SceneRef) record integrators and
//! shaders receive. Each entry's signature is thus written twice in all: in
//! its record and in the SDK shim that implements it; the calls here go
//! through the records' accessors.
//!
//! Objects form a DAG: a parent holds its children's handles, so a child can
//! never be destroyed before the parents that point at it.

mod handles;
mod services;
pub(crate) mod volumes;

pub use handles::{Camera, CreateArgs, Integrator, Light, Object, ObjectBuilder, Shader};
pub use services::{PrepareServices, SceneRecord, Services, ServicesTable};

#[cfg(doc)]
use crate::abi::STATUS_ERROR;
use crate::abi::{ErrSink, STATUS_OK, STATUS_PANIC};
use std::ffi::c_void;

/// A cold call that a plugin refused or panicked in.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{}", self.describe())]
pub struct CallError {
    /// The entry called (`create`, `prepare`, `bounds`...).
    pub entry: &'static str,
    /// The plugin panicked (rather than refusing with an error).
    pub panicked: bool,
    /// The parameter key path concerned, or empty.
    pub key: String,
    /// The plugin's message.
    pub message: String,
}

impl CallError {
    fn describe(&self) -> String {
        if self.panicked {
            format!("panicked in {}: {}", self.entry, self.message)
        } else if self.key.is_empty() {
            self.message.clone()
        } else {
            format!("{}: {}", self.key, self.message)
        }
    }
}

/// Collects what a plugin reports through an [`ErrSink`].
#[derive(Default)]
pub(crate) struct Collected {
    /// The status the plugin reported with (0 while nothing was reported).
    status: i32,
    key: String,
    msg: String,
}

unsafe extern "C" fn collect(
    ctx: *mut c_void,
    status: i32,
    key: *const u8,
    klen: usize,
    msg: *const u8,
    mlen: usize,
) {
    // SAFETY: `ctx` is the `Collected` the sink was made from, alive for the
    // call; the plugin passes valid byte ranges (decoded lossily regardless).
    unsafe {
        let c = &mut *(ctx as *mut Collected);
        c.status = status;
        c.key = String::from_utf8_lossy(std::slice::from_raw_parts(key, klen)).into_owned();
        c.msg = String::from_utf8_lossy(std::slice::from_raw_parts(msg, mlen)).into_owned();
    }
}

impl Collected {
    /// A sink writing into `self`, valid while `self` is borrowed.
    pub(crate) fn sink(&mut self) -> ErrSink {
        ErrSink {
            ctx: self as *mut Collected as *mut c_void,
            report: collect,
        }
    }

    /// The outcome of a cold call that returned `status` (for `create`,
    /// which returns a pointer: [`STATUS_ERROR`] when it returned null).
    pub(crate) fn result(&mut self, status: i32, entry: &'static str) -> Result<(), CallError> {
        if status == STATUS_OK {
            return Ok(());
        }
        Err(CallError {
            entry,
            panicked: status == STATUS_PANIC || self.status == STATUS_PANIC,
            key: std::mem::take(&mut self.key),
            message: if self.msg.is_empty() {
                format!("failed in {entry} without a message (status {status})")
            } else {
                std::mem::take(&mut self.msg)
            },
        })
    }
}
