//! The plain header every plugin exports, read with `libloading` before any
//! plugin code runs: it is what lets rtk refuse a library built against
//! another ABI, or with `panic = "abort"`, without calling it.

use crate::ABI_VERSION;
use abi_stable::StableAbi;

/// Kinds of plugin.
#[repr(u32)]
#[derive(StableAbi, Clone, Copy, Debug, PartialEq, Eq)]
pub enum PluginKind {
    /// An object class (primitive, aggregate, transform, CSG).
    Object = 1,
    /// A shader (material).
    Shader = 2,
    /// An integrator.
    Integrator = 3,
    /// A camera.
    Camera = 4,
    /// A light.
    Light = 5,
}

impl PluginKind {
    /// Decode a raw kind.
    pub fn from_u32(v: u32) -> Option<Self> {
        Some(match v {
            1 => Self::Object,
            2 => Self::Shader,
            3 => Self::Integrator,
            4 => Self::Camera,
            5 => Self::Light,
            _ => return None,
        })
    }
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Object => "object",
            Self::Shader => "shader",
            Self::Integrator => "integrator",
            Self::Camera => "camera",
            Self::Light => "light",
        }
    }
}

/// Magic bytes opening [`PluginHeader`].
pub const PLUGIN_MAGIC: [u8; 8] = *b"RTKPLUG\0";
/// Name of the exported header symbol.
pub const PLUGIN_HEADER_SYMBOL: &[u8] = b"RTK_PLUGIN_HEADER\0";

/// Plain data every plugin exports under [`PLUGIN_HEADER_SYMBOL`]. The host
/// reads it without calling any plugin code, and refuses the library if the
/// magic, the ABI version, the kernel version or the panic strategy is wrong.
/// Strings are NUL-padded fixed arrays so that no pointer needs relocating.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PluginHeader {
    /// [`PLUGIN_MAGIC`].
    pub magic: [u8; 8],
    /// Size of this struct as the plugin saw it.
    pub header_size: u32,
    /// [`ABI_VERSION`] the plugin was built against.
    pub abi_version: u32,
    /// [`PluginKind`] as `u32`.
    pub kind: u32,
    /// 1 if built with `panic = "unwind"`, 0 for `panic = "abort"`.
    pub panic_unwind: u32,
    /// `rtk-abi` version the plugin was built against, NUL-padded (the
    /// field ABI 1 and 2 called the kernel version: same place, same size).
    pub abi_crate_version: [u8; 32],
    /// Class name, NUL-padded.
    pub class_name: [u8; 64],
}

impl PluginHeader {
    /// Build a header at compile time (used by the export macros).
    pub const fn new(kind: PluginKind, class_name: &str, panic_unwind: bool) -> Self {
        Self {
            magic: PLUGIN_MAGIC,
            header_size: std::mem::size_of::<PluginHeader>() as u32,
            abi_version: ABI_VERSION,
            kind: kind as u32,
            panic_unwind: panic_unwind as u32,
            abi_crate_version: pad::<32>(crate::ABI_CRATE_VERSION),
            class_name: pad::<64>(class_name),
        }
    }

    /// The class name as a string (up to the first NUL).
    pub fn class_name(&self) -> String {
        unpad(&self.class_name)
    }

    /// The `rtk-abi` version as a string.
    pub fn abi_crate_version(&self) -> String {
        unpad(&self.abi_crate_version)
    }
}

const fn pad<const N: usize>(s: &str) -> [u8; N] {
    let b = s.as_bytes();
    assert!(b.len() < N, "name too long for the plugin header");
    let mut out = [0u8; N];
    let mut i = 0;
    while i < b.len() {
        out[i] = b[i];
        i += 1;
    }
    out
}

fn unpad(b: &[u8]) -> String {
    let end = b.iter().position(|&c| c == 0).unwrap_or(b.len());
    String::from_utf8_lossy(&b[..end]).into_owned()
}
