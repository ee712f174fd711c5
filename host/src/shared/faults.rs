//! Naming the plugin behind a fault the host cannot catch: an abort (or an
//! illegal instruction, a floating-point trap) inside a plugin, and a
//! plugin call that never returns.
//!
//! Why by the stack and not by a "current plugin" slot: a slot would be
//! written around every call into a plugin — per ray, per node, per shading
//! call — which the guide's hot-path rule forbids and which costs more than
//! the whole boundary. The fault is rare; the lookup happens only then. The
//! handler walks its own stack (`backtrace`, warmed up at installation so
//! that its loader runs outside the handler) and asks the dynamic loader
//! which library holds each return address (`dladdr`); the innermost frame
//! in a `librtk_<class>` library names the plugin. A call that never
//! returns is found the same way: the watchdog signals each render thread,
//! whose handler reports the plugin it is in.
//!
//! What stays: the signal's own exit status (the handler re-raises it with
//! the default action), so a shell or a farm still sees "killed by SIGABRT".
//! Segmentation faults are left to Rust's handler, which reports stack
//! overflows.

#[cfg(all(target_os = "linux", target_env = "gnu"))]
mod imp {
    use std::ffi::{c_int, c_void, CStr};
    use std::sync::Mutex;
    use std::sync::Once;

    extern "C" {
        /// glibc's `backtrace(3)`.
        fn backtrace(buffer: *mut *mut c_void, size: c_int) -> c_int;
    }

    /// The render threads, for the hang watchdog to signal.
    static THREADS: Mutex<Vec<libc::pthread_t>> = Mutex::new(Vec::new());

    /// Most frames walked.
    const FRAMES: usize = 128;

    /// Write `parts` to stderr with `write(2)` (async-signal-safe).
    fn say(parts: &[&[u8]]) {
        for p in parts {
            // SAFETY: writing a live byte slice to fd 2; a short or failed
            // write loses a message, nothing more.
            unsafe { libc::write(2, p.as_ptr() as *const c_void, p.len()) };
        }
    }

    /// The innermost plugin library on this thread's stack: (class, path).
    fn plugin_on_stack(buf: &mut [*mut c_void; FRAMES]) -> Option<(&'static [u8], &'static [u8])> {
        // SAFETY: `backtrace` fills at most FRAMES entries of the buffer.
        let n = unsafe { backtrace(buf.as_mut_ptr(), FRAMES as c_int) }.max(0) as usize;
        for &pc in &buf[..n] {
            // SAFETY: `dladdr` only reads the loader's tables for `pc` and
            // writes the `Dl_info` it is given.
            let mut info: libc::Dl_info = unsafe { std::mem::zeroed() };
            if unsafe { libc::dladdr(pc as *const c_void, &mut info) } == 0
                || info.dli_fname.is_null()
            {
                continue;
            }
            // SAFETY: the loader's file name is a NUL-terminated string that
            // lives as long as the library stays loaded (plugins are never
            // unloaded while they run).
            let path: &'static [u8] = unsafe { CStr::from_ptr(info.dli_fname) }.to_bytes();
            let file = path.rsplit(|&b| b == b'/').next().unwrap_or(path);
            if let Some(class) = file
                .strip_prefix(b"librtk_")
                .and_then(|f| f.strip_suffix(b".so"))
            {
                return Some((class, path));
            }
        }
        None
    }

    fn signal_name(sig: c_int) -> &'static [u8] {
        match sig {
            libc::SIGABRT => b"SIGABRT (abort)",
            libc::SIGILL => b"SIGILL (illegal instruction)",
            libc::SIGFPE => b"SIGFPE (arithmetic trap)",
            _ => b"a fatal signal",
        }
    }

    extern "C" fn on_fatal(sig: c_int) {
        let mut buf = [std::ptr::null_mut(); FRAMES];
        match plugin_on_stack(&mut buf) {
            Some((class, path)) => say(&[
                b"error: plugin `",
                class,
                b"` (",
                path,
                b") stopped the process with ",
                signal_name(sig),
                b"\n",
            ]),
            None => say(&[
                b"error: rtk stopped with ",
                signal_name(sig),
                b" outside any plugin\n",
            ]),
        }
        // SAFETY: restoring the default action and re-raising is how a
        // handler keeps the signal's exit status; both are async-signal-safe.
        unsafe {
            libc::signal(sig, libc::SIG_DFL);
            libc::raise(sig);
        }
    }

    extern "C" fn on_watchdog(_sig: c_int) {
        let mut buf = [std::ptr::null_mut(); FRAMES];
        if let Some((class, path)) = plugin_on_stack(&mut buf) {
            say(&[
                b"  a render thread is inside plugin `",
                class,
                b"` (",
                path,
                b")\n",
            ]);
        }
    }

    pub fn install() {
        static ONCE: Once = Once::new();
        ONCE.call_once(|| {
            // Warm up: the first `backtrace` loads libgcc_s, which must not
            // happen inside a handler.
            let mut buf = [std::ptr::null_mut(); FRAMES];
            let _ = plugin_on_stack(&mut buf);
            for (sig, h) in [
                (libc::SIGABRT, on_fatal as extern "C" fn(c_int)),
                (libc::SIGILL, on_fatal),
                (libc::SIGFPE, on_fatal),
                (libc::SIGUSR2, on_watchdog),
            ] {
                // SAFETY: installing a handler that only calls
                // async-signal-safe functions (write, dladdr, the
                // unwinder warmed up above, signal, raise).
                unsafe { libc::signal(sig, h as libc::sighandler_t) };
            }
        });
    }

    pub fn register_thread() {
        // SAFETY: `pthread_self` has no preconditions.
        let me = unsafe { libc::pthread_self() };
        if let Ok(mut t) = THREADS.lock() {
            t.push(me);
        }
    }

    pub fn report_stuck_threads() {
        let threads = THREADS.lock().map(|t| t.clone()).unwrap_or_default();
        for t in threads {
            // SAFETY: the ids are of the pool's threads, which live until
            // the process exits (the pool is never dropped before that).
            unsafe { libc::pthread_kill(t, libc::SIGUSR2) };
        }
        std::thread::sleep(std::time::Duration::from_millis(200));
    }
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
mod imp {
    pub fn install() {}
    pub fn register_thread() {}
    pub fn report_stuck_threads() {}
}

/// Install the handlers that name the plugin behind an abort (SIGABRT,
/// SIGILL, SIGFPE) and answer the hang watchdog (SIGUSR2). Idempotent.
pub(crate) fn install() {
    imp::install()
}

/// Record the calling thread as a render thread (the pool's start handler).
pub(crate) fn register_thread() {
    imp::register_thread()
}

/// Ask every render thread which plugin it is in; each inside one says so
/// on stderr.
pub(crate) fn report_stuck_threads() {
    imp::report_stuck_threads()
}
