//! What several commands share: the thread pool, loading a scene, reading
//! images with their error metrics (`rtk diff`, `rtk converge`), writing
//! them atomically (`rtk render`, `rtk merge`, `rtk converge`), and making
//! messages safe to print.

pub(crate) mod faults;
pub(crate) mod images;
pub(crate) mod output;
pub(crate) mod scene;
pub(crate) mod threads;

/// An error message made safe for the terminal: control characters that
/// reached it from a scene or a file (escape sequences) escaped, and each
/// line cut to a readable length. The shell's own errors are escaped
/// already; this covers the host's (paths, output names).
pub(crate) fn printable(msg: &str) -> String {
    msg.split('\n')
        .map(|l| rtk_shell::error::shown(l, rtk_shell::error::MAX_SHOWN_MESSAGE))
        .collect::<Vec<_>>()
        .join("\n")
}
