//! What several commands share: reading images and their error metrics
//! (`rtk diff`, `rtk converge`) and writing them atomically (`rtk render`,
//! `rtk merge`, `rtk converge`).

pub(crate) mod images;
pub(crate) mod output;
