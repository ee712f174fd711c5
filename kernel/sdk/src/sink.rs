//! Errors of cold calls, from both sides: what a plugin reports through an
//! [`ErrSink`] is collected into a [`CallError`]. Shared by the plugin-side
//! callers ([`Child`](crate::Child)) and the host's handles (`rtk-handles`),
//! so a failure reads the same wherever it was caught.

#[cfg(doc)]
use rtk_abi::STATUS_ERROR;
use rtk_abi::{ErrSink, STATUS_OK, STATUS_PANIC};
use std::ffi::c_void;

/// A cold call that a plugin refused or panicked in.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{}", self.describe())]
pub struct CallError {
    /// The entry called (`create`, `prepare`, `bounds`...).
    pub entry: &'static str,
    /// The class of the object called.
    pub class: &'static str,
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
pub struct Collected {
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
    pub fn sink(&mut self) -> ErrSink {
        ErrSink {
            ctx: self as *mut Collected as *mut c_void,
            report: collect,
        }
    }

    /// The outcome of a cold call that returned `status` (for `create`,
    /// which returns a pointer: [`STATUS_ERROR`] when it returned null).
    pub fn result(
        &mut self,
        status: i32,
        entry: &'static str,
        class: &'static str,
    ) -> Result<(), CallError> {
        if status == STATUS_OK {
            return Ok(());
        }
        Err(CallError {
            entry,
            class,
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

impl From<CallError> for crate::PluginError {
    /// A child's failure as its parent reports it: naming the child's class.
    fn from(e: CallError) -> Self {
        crate::PluginError::msg(format!("child of class `{}`: {e}", e.class))
    }
}
