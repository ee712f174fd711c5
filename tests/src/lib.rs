//! Helpers for the integration tests: build the workspace's binary and
//! plugins once (into the same target directory the tests run from), build
//! the out-of-workspace fixture plugins once, run `rtk`, read images back.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

/// The workspace root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("workspace root")
        .to_path_buf()
}

/// `target/` and the profile folder the running test binary was built in
/// (`debug`, `release`...), from the test executable's own path.
fn target_and_profile() -> (PathBuf, String) {
    let exe = std::env::current_exe().expect("current exe");
    // target/<profile>/deps/<test-binary>
    let profile_dir = exe.parent().and_then(Path::parent).expect("profile dir");
    let target = profile_dir.parent().expect("target dir").to_path_buf();
    let profile = profile_dir
        .file_name()
        .expect("profile")
        .to_string_lossy()
        .into_owned();
    (target, profile)
}

fn profile_args(profile: &str) -> Vec<String> {
    match profile {
        "debug" => vec![],
        "release" => vec!["--release".into()],
        p => vec!["--profile".into(), p.into()],
    }
}

fn cargo() -> Command {
    Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
}

fn run_cargo(mut c: Command, what: &str) {
    let out = c
        .output()
        .unwrap_or_else(|e| panic!("running cargo for {what}: {e}"));
    assert!(
        out.status.success(),
        "cargo failed building {what}:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The folder holding `rtk` and the built-in plugins, built once per test run.
pub fn bin_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let (target, profile) = target_and_profile();
        let mut c = cargo();
        c.current_dir(root())
            .args([
                "build",
                "--workspace",
                "--exclude",
                "rtk-tests",
                "--target-dir",
            ])
            .arg(&target)
            .args(profile_args(&profile));
        run_cargo(c, "the workspace");
        target.join(&profile)
    })
}

/// The `rtk` executable.
pub fn rtk_path() -> PathBuf {
    bin_dir().join(format!("rtk{}", std::env::consts::EXE_SUFFIX))
}

/// A command running `rtk` with the given arguments.
pub fn rtk(args: &[&str]) -> Command {
    let mut c = Command::new(rtk_path());
    c.args(args)
        .env_remove("RTK_PLUGIN_PATH")
        .env("RUST_BACKTRACE", "0");
    c
}

/// The fixture plugins of `tests/fixtures`, built once: returns the folder
/// holding `librtk_<name>.so`. `abortplugin` is built with `panic = "abort"`.
pub fn fixtures_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let (target, profile) = target_and_profile();
        let ftarget = target.join("fixtures");
        let manifest = root().join("tests/fixtures/Cargo.toml");
        let mut c = cargo();
        c.args([
            "build",
            "-p",
            "rtk_panicky",
            "-p",
            "rtk_notplugin",
            "-p",
            "rtk_dropin",
            "-p",
            "rtk_brokenagg",
            "-p",
            "rtk_brokenshader",
            "-p",
            "rtk_brokennearest",
            "-p",
            "rtk_brokenbounds",
            "-p",
            "rtk_brokenrace",
            "-p",
            "rtk_panickyshader",
            "-p",
            "rtk_panickylight",
            "-p",
            "rtk_panickycamera",
            "-p",
            "rtk_panickyintegrator",
            "-p",
            "rtk_keeper",
            "-p",
            "rtk_streamsphere",
            "-p",
            "rtk_brokenstream",
            "--manifest-path",
        ])
        .arg(&manifest)
        .arg("--target-dir")
        .arg(&ftarget)
        .args(profile_args(&profile));
        run_cargo(c, "fixture plugins");
        let mut c = cargo();
        c.args(["rustc", "-p", "rtk_abortplugin", "--lib", "--manifest-path"])
            .arg(&manifest)
            .arg("--target-dir")
            .arg(&ftarget)
            .args(profile_args(&profile))
            .args(["--", "-C", "panic=abort"]);
        run_cargo(c, "the panic=abort fixture");
        ftarget.join(&profile)
    })
}

/// An edit of one kernel source file: (file under `kernel/`, from, to).
type KernelEdit = (&'static str, &'static str, &'static str);

/// A plugin built against a kernel whose `Ray` record differs (its
/// `generation` field is `u64`): a copy of `kernel/` edited at test time.
pub fn other_abi_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        other_kernel_plugin(
            "otherabi",
            None,
            &[(
                "abi/src/values.rs",
                "pub generation: u32,",
                "pub generation: u64,",
            )],
        )
    })
}

/// A plugin whose header says ABI 2 and whose `rtk-abi` is 2.0.0: what a
/// plugin built before Kernel v3 looks like to the loader.
pub fn abi_v2_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| other_kernel_plugin("abiv2", Some("2.0.0"), &[]))
}

/// A plugin built against a kernel whose `rtk-abi` is one minor later than
/// this host's (entries appended)
/// and whose BVH differs (`rtk-accel` at 0.9.0, with another culling
/// margin): it loads, since only the ABI crate's major version counts.
pub fn later_minor_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        other_kernel_plugin(
            "laterminor",
            Some(&later_minor_version()),
            &[
                (
                    "accel/Cargo.toml",
                    "version.workspace = true",
                    "version = \"0.9.0\"",
                ),
                ("accel/src/lib.rs", "1.0 / 16384.0", "1.0 / 8192.0"),
            ],
        )
    })
}

/// A plugin whose object record has no stream entries, as one built before
/// rtk-abi 3.1 has none: the panicky body against a copy of the kernel
/// whose SDK leaves every appended entry out of the records it builds
/// (they read as `None` to the host, as a shorter record's do).
pub fn without_streams_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        other_kernel_plugin(
            "nostreams",
            None,
            &[(
                "sdk/src/gen.rs",
                "$( $name3: Some($name3::<T, D>), )*",
                "$( $name3: None, )*",
            )],
        )
    })
}

/// This host's `rtk-abi` version with the minor one later and patch 0.
fn later_minor_version() -> String {
    format!(
        "{}.{}.0",
        rtk_kernel::abi::ABI_VERSION,
        rtk_kernel::abi::ABI_MINOR + 1
    )
}

/// Build the panicky fixture as class `class` against a copy of `kernel/`
/// (every crate of it) with `rtk-abi` at `abi_version` (the ABI version is
/// its major) and the given source edits.
fn other_kernel_plugin(class: &str, abi_version: Option<&str>, edits: &[KernelEdit]) -> PathBuf {
    let (target, profile) = target_and_profile();
    let src = target.join("fixture-src").join(class);
    let _ = std::fs::remove_dir_all(&src);
    copy_dir(&root().join("kernel"), &src.join("kernel"));
    for (file, from, to) in edits {
        edit_file(&src.join("kernel").join(file), from, to);
    }
    if let Some(v) = abi_version {
        edit_file(
            &src.join("kernel/abi/Cargo.toml"),
            &format!("version = \"{}\"", rtk_kernel::abi::ABI_CRATE_VERSION),
            &format!("version = \"{v}\""),
        );
    }
    let deps = workspace_dependencies();
    for dir in ["", "abi", "geom", "sdk", "accel", "handles"] {
        let path = src.join("kernel").join(dir).join("Cargo.toml");
        let toml = std::fs::read_to_string(&path).expect("kernel toml");
        std::fs::write(&path, standalone_manifest(&toml, &deps, dir.is_empty()))
            .expect("kernel toml");
    }
    let plug = src.join(class);
    std::fs::create_dir_all(plug.join("src")).expect("mkdir");
    std::fs::write(
        plug.join("Cargo.toml"),
        format!(
            "[package]\nname = \"rtk_{class}\"\nversion = \"0.1.0\"\nedition = \"2021\"\n\n[lib]\ncrate-type = [\"cdylib\"]\n\n\
             [dependencies]\nrtk-kernel = {{ path = \"../kernel\" }}\n\n[workspace]\n\n[profile.dev.package.\"*\"]\nopt-level = 3\n"
        ),
    )
    .expect("toml");
    let lib = std::fs::read_to_string(root().join("tests/fixtures/panicky/src/body.rs")).expect("panicky source")
        + &format!("\nrtk_kernel::export_object!(Panicky, class = \"{class}\", doc = \"Test fixture: another kernel.\");\n");
    std::fs::write(plug.join("src/lib.rs"), lib).expect("lib.rs");
    let _ = std::fs::copy(
        root().join("tests/fixtures/Cargo.lock"),
        plug.join("Cargo.lock"),
    );
    let ftarget = target.join("fixtures");
    let mut c = cargo();
    c.arg("build")
        .arg("--manifest-path")
        .arg(plug.join("Cargo.toml"))
        .arg("--target-dir")
        .arg(&ftarget)
        .args(profile_args(&profile));
    run_cargo(c, &format!("the {class} fixture"));
    ftarget.join(&profile)
}

/// Replace `from` by `to` once in a file; the edit must change it.
fn edit_file(path: &Path, from: &str, to: &str) {
    let text = std::fs::read_to_string(path).expect("kernel source");
    let edited = text.replacen(from, to, 1);
    assert_ne!(text, edited, "the edit must change {}", path.display());
    std::fs::write(path, edited).expect("write kernel source");
}

/// The main workspace's `[workspace.dependencies]`, as `name -> value` lines.
fn workspace_dependencies() -> Vec<(String, String)> {
    let text = std::fs::read_to_string(root().join("Cargo.toml")).expect("workspace toml");
    let table = text
        .split("[workspace.dependencies]")
        .nth(1)
        .expect("workspace dependencies")
        .split("\n[")
        .next()
        .unwrap_or("");
    table
        .lines()
        .filter(|l| !l.trim_start().starts_with('#'))
        .filter_map(|l| l.split_once(" = "))
        .map(|(k, v)| (k.trim().to_string(), v.trim().to_string()))
        .collect()
}

/// A kernel crate's manifest that stands alone: the workspace's fields and
/// dependencies written out (the copy belongs to no workspace).
fn standalone_manifest(toml: &str, deps: &[(String, String)], facade: bool) -> String {
    let mut out = String::new();
    for line in toml.lines() {
        let l = line.trim();
        if l == "[lints]"
            || l == "workspace = true"
            || l.starts_with("rust-version.workspace")
            || l.starts_with("license.workspace")
        {
            continue;
        }
        if l == "version.workspace = true" {
            out.push_str("version = \"0.1.0\"\n");
        } else if l == "edition.workspace = true" {
            out.push_str("edition = \"2021\"\n");
        } else if let Some(name) = l.strip_suffix(".workspace = true") {
            let v = &deps
                .iter()
                .find(|(k, _)| k == name)
                .expect("a workspace dependency")
                .1;
            let v = match v.strip_prefix("{ path = \"kernel/") {
                Some(rest) if facade => format!("{{ path = \"{rest}"),
                Some(rest) => format!("{{ path = \"../{rest}"),
                None => v.clone(),
            };
            out.push_str(&format!("{name} = {v}\n"));
        } else {
            out.push_str(line);
            out.push('\n');
        }
    }
    out
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("mkdir");
    for e in std::fs::read_dir(from).expect("read_dir").flatten() {
        let p = e.path();
        if p.is_dir() {
            copy_dir(&p, &to.join(e.file_name()));
        } else {
            std::fs::copy(&p, to.join(e.file_name())).expect("copy");
        }
    }
}

/// A temporary plugin folder holding copies of the named libraries from `dir`.
pub fn plugin_folder(dir: &Path, classes: &[&str]) -> tempfile::TempDir {
    let t = tempfile::tempdir().expect("tempdir");
    for c in classes {
        let name = format!(
            "{}rtk_{c}{}",
            std::env::consts::DLL_PREFIX,
            std::env::consts::DLL_SUFFIX
        );
        std::fs::copy(dir.join(&name), t.path().join(&name))
            .unwrap_or_else(|e| panic!("copy {name}: {e}"));
    }
    t
}

/// The result of running `rtk`.
pub struct Run {
    /// Exit status was success.
    pub ok: bool,
    /// Standard output.
    pub stdout: String,
    /// Standard error.
    pub stderr: String,
}

impl Run {
    /// From a process output.
    pub fn from(o: Output) -> Self {
        Run {
            ok: o.status.success(),
            stdout: String::from_utf8_lossy(&o.stdout).into_owned(),
            stderr: String::from_utf8_lossy(&o.stderr).into_owned(),
        }
    }
    /// The `--stats` JSON.
    pub fn stats(&self) -> serde_json::Value {
        serde_json::from_str(&self.stdout)
            .unwrap_or_else(|e| panic!("stats JSON: {e}\n{}", self.stdout))
    }
}

/// Write `scene` into a temporary folder and render it to EXR with `args`.
/// Returns the run and, on success, the linear image.
pub fn render_scene(scene: &str, args: &[&str]) -> (Run, Option<Image>) {
    let dir = tempfile::tempdir().expect("tempdir");
    let sp = dir.path().join("scene.toml");
    std::fs::write(&sp, scene).expect("write scene");
    render_file(&sp, dir.path(), args)
}

/// Render a scene file to an EXR in `out_dir`.
pub fn render_file(scene: &Path, out_dir: &Path, args: &[&str]) -> (Run, Option<Image>) {
    let out = out_dir.join("out.exr");
    let mut a = vec![
        "render",
        scene.to_str().expect("utf8"),
        "-o",
        out.to_str().expect("utf8"),
        "-q",
    ];
    a.extend_from_slice(args);
    let run = Run::from(rtk(&a).output().expect("run rtk"));
    let img = if run.ok {
        Some(Image::read(&out))
    } else {
        None
    };
    if !run.ok {
        assert!(!out.exists(), "a failed render must leave no output file");
    }
    (run, img)
}

/// A linear RGB image.
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Row-major RGB.
    pub data: Vec<f32>,
}

impl Image {
    /// Read an EXR.
    pub fn read(p: &Path) -> Self {
        let img = image::open(p)
            .unwrap_or_else(|e| panic!("reading {}: {e}", p.display()))
            .into_rgb32f();
        Image {
            width: img.width(),
            height: img.height(),
            data: img.into_raw(),
        }
    }
    /// Pixel (x, y).
    pub fn px(&self, x: u32, y: u32) -> [f32; 3] {
        let i = ((y * self.width + x) * 3) as usize;
        [self.data[i], self.data[i + 1], self.data[i + 2]]
    }
}

/// Build an out-of-tree plugin crate (as `rtk new` writes) with
/// `cargo build --release`, in the fixtures' target directory so that the
/// kernel built for the fixtures is reused (with the fixtures' lock file, so
/// the dependencies resolve to the same versions). Returns the folder
/// holding its library.
pub fn build_plugin_crate(dir: &Path) -> PathBuf {
    let (target, _) = target_and_profile();
    let ftarget = target.join("fixtures");
    if !dir.join("Cargo.lock").exists() {
        let _ = std::fs::copy(
            root().join("tests/fixtures/Cargo.lock"),
            dir.join("Cargo.lock"),
        );
    }
    let mut c = cargo();
    c.current_dir(dir)
        .args(["build", "--release", "--target-dir"])
        .arg(&ftarget);
    run_cargo(c, &dir.display().to_string());
    ftarget.join("release")
}

/// A world built in this process from scene text (written to a temporary
/// folder, so relative paths resolve there), with the built plugins.
pub fn world_from(toml: &str) -> rtk_shell::World {
    world_with_plugins(toml, &[bin_dir()])
}

/// [`world_from`] with these plugin folders (searched in order).
pub fn world_with_plugins(toml: &str, dirs: &[&Path]) -> rtk_shell::World {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("scene.toml");
    std::fs::write(&path, toml).expect("scene");
    let mut reg = rtk_shell::Registry::new(rtk_shell::PluginPath {
        dirs: dirs.iter().map(|d| d.to_path_buf()).collect(),
    });
    rtk_shell::load(&path, &[], &mut reg, &rtk_shell::Sequential).unwrap_or_else(|e| panic!("{e}"))
}

/// A file under `../shared` (beside the checkout: the data and anchors rtk
/// may use but not copy). A test that needs it fails when it is absent —
/// a pass must mean it ran — unless `RTK_NO_SHARED=1` is set, which skips
/// the test and says so. (CI has `../shared` and never sets it.)
pub fn shared(rel: &str) -> Option<PathBuf> {
    let p = root().join("../shared").join(rel);
    if p.exists() {
        return Some(p);
    }
    if std::env::var("RTK_NO_SHARED").as_deref() == Ok("1") {
        eprintln!("skipped (RTK_NO_SHARED=1): needs ../shared/{rel}");
        return None;
    }
    panic!(
        "this test needs ../shared/{rel} ({} is absent): put the shared data beside the \
         checkout, or set RTK_NO_SHARED=1 to skip the tests that need it",
        p.display()
    );
}
