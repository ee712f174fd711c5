//! `rtk`: render TOML scenes with plugin object classes, shaders,
//! integrators, cameras and lights. The commands live in the library
//! ([`rtk_host::cli`]), which the Python module shares.

fn main() {
    rtk_host::cli::main()
}
