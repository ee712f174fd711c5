//! The hostile-input catalogue (issue 11): malformed or hostile scenes,
//! meshes, files and arguments, each with the error it must produce. Every
//! case runs the real `rtk` binary and must exit non-zero, say every
//! expected substring (file:line:col, object, key, what was expected),
//! finish within [`DEADLINE`] (no hang on a FIFO, no endless read of
//! `/dev/zero`), print no raw control character, and leave nothing behind
//! in its folder (no image, no temporary file).
//!
//! `bad_scenes.rs` has the first, simpler errors; the cases here do not
//! repeat them.

use rtk_tests::*;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The longest any case may take: every refusal comes before rendering.
const DEADLINE: Duration = Duration::from_secs(30);

/// The scene the cases edit. Line numbers matter: the cases name them.
const GOOD: &str = r#"[render]
width = 8
height = 8
root = "world"
integrator = "normals"

[cameras.main]
class = "pinhole"
eye = [0.0, 0.0, 5.0]

[lights.sun]
class = "point"
position = [0.0, 5.0, 5.0]
intensity = [10.0, 10.0, 10.0]

[shaders.red]
class = "lambert"
albedo = [0.8, 0.1, 0.1]

[objects.ball]
class = "sphere"
center = [0.0, 0.0, 0.0]
radius = 1.0

[objects.tri]
class = "mesh"
file = "tri.obj"

[objects.world]
class = "list"
children = [{ object = "ball", shader = "red" }, { object = "tri" }]
"#;

/// The mesh the good scene uses.
const TRI_OBJ: &str = "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n";

/// A file a case puts in its folder before running.
enum Extra {
    /// A file with these bytes.
    Bytes(&'static str, Vec<u8>),
    /// A FIFO (nobody ever writes to it).
    Fifo(&'static str),
    /// A sparse file of this many bytes.
    Sparse(&'static str, u64),
    /// A symbolic link to a target.
    Link(&'static str, &'static str),
    /// A folder.
    Dir(&'static str),
}

/// One hostile input and the error it must produce.
struct Case {
    name: &'static str,
    scene: String,
    /// The scene argument, when not the case's `scene.toml`.
    scene_arg: Option<String>,
    extra: Vec<Extra>,
    /// Further arguments; `{dir}` stands for the case's folder.
    args: Vec<String>,
    /// Substrings of stderr; `{dir}` stands for the case's folder.
    expect: Vec<String>,
    /// Substrings stderr must not have.
    refuse: Vec<String>,
    /// Pass `-o {dir}/out.exr` (else the scene's output, or `scene.png`).
    output: bool,
    /// Limit the process's address space (KiB), as `ulimit -v` does.
    address_space_kb: Option<u64>,
    /// The whole command line instead of `render SCENE -q [-o ...] ARGS`.
    command: Option<Vec<String>>,
}

/// A case on its own scene text.
fn scene(name: &'static str, text: impl Into<String>, expect: &[&str]) -> Case {
    Case {
        name,
        scene: text.into(),
        scene_arg: None,
        extra: vec![Extra::Bytes("tri.obj", TRI_OBJ.into())],
        args: vec![],
        expect: expect.iter().map(|s| s.to_string()).collect(),
        refuse: vec![],
        output: true,
        address_space_kb: None,
        command: None,
    }
}

/// A case on the good scene with `from` replaced by `to`.
fn edit(name: &'static str, from: &str, to: &str, expect: &[&str]) -> Case {
    assert!(GOOD.contains(from), "{name}: {from:?} is not in the scene");
    scene(name, GOOD.replacen(from, to, 1), expect)
}

/// A case on the good scene with its mesh file replaced.
fn mesh(name: &'static str, file: &'static str, bytes: &[u8], expect: &[&str]) -> Case {
    edit(
        name,
        "file = \"tri.obj\"",
        &format!("file = \"{file}\""),
        expect,
    )
    .with(Extra::Bytes(file, bytes.to_vec()))
}

impl Case {
    fn with(mut self, e: Extra) -> Self {
        self.extra.push(e);
        self
    }
    fn args(mut self, a: &[&str]) -> Self {
        self.args.extend(a.iter().map(|s| s.to_string()));
        self
    }
    fn scene_arg(mut self, a: &str) -> Self {
        self.scene_arg = Some(a.to_string());
        self
    }
    fn refuse(mut self, r: &[&str]) -> Self {
        self.refuse.extend(r.iter().map(|s| s.to_string()));
        self
    }
    fn no_output(mut self) -> Self {
        self.output = false;
        self
    }
    fn command(mut self, c: &[&str]) -> Self {
        self.command = Some(c.iter().map(|s| s.to_string()).collect());
        self
    }
    fn address_space_kb(mut self, kb: u64) -> Self {
        self.address_space_kb = Some(kb);
        self
    }
}

fn make(dir: &Path, e: &Extra) {
    match e {
        Extra::Bytes(name, b) => std::fs::write(dir.join(name), b).expect("write"),
        Extra::Fifo(name) => {
            let ok = Command::new("mkfifo")
                .arg(dir.join(name))
                .status()
                .expect("mkfifo");
            assert!(ok.success(), "mkfifo");
        }
        Extra::Sparse(name, len) => std::fs::File::create(dir.join(name))
            .and_then(|f| f.set_len(*len))
            .expect("sparse file"),
        Extra::Link(name, target) => {
            let _ = std::fs::remove_file(dir.join(name));
            std::os::unix::fs::symlink(target, dir.join(name)).expect("symlink")
        }
        Extra::Dir(name) => std::fs::create_dir_all(dir.join(name)).expect("mkdir"),
    }
}

fn names_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .expect("read_dir")
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// Run `rtk` with `args` in `cwd`, killing it at the deadline; stdout and
/// stderr go to files in `logs` (a pipe left unread could block it).
fn run_bounded(cwd: &Path, logs: &Path, args: &[String], kb: Option<u64>) -> Result<Run, String> {
    let (out, err) = (logs.join("stdout"), logs.join("stderr"));
    let mut cmd = match kb {
        None => rtk(&[]),
        Some(kb) => {
            let mut c = Command::new("sh");
            c.arg("-c")
                .arg(format!("ulimit -v {kb} && exec \"$0\" \"$@\""))
                .arg(rtk_path())
                .env_remove("RTK_PLUGIN_PATH")
                .env("RUST_BACKTRACE", "0");
            c
        }
    };
    cmd.args(args)
        .current_dir(cwd)
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&out).expect("log"))
        .stderr(std::fs::File::create(&err).expect("log"));
    let mut child = cmd.spawn().map_err(|e| format!("spawn: {e}"))?;
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().map_err(|e| e.to_string())? {
            break s;
        }
        if start.elapsed() > DEADLINE {
            let _ = child.kill();
            let _ = child.wait();
            return Err(format!("still running after {DEADLINE:?}: it hangs"));
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    Ok(Run {
        ok: status.success(),
        stdout: String::from_utf8_lossy(&std::fs::read(&out).unwrap_or_default()).into_owned(),
        stderr: String::from_utf8_lossy(&std::fs::read(&err).unwrap_or_default()).into_owned(),
    })
}

/// Run one case; the error says what went wrong.
fn run(case: &Case) -> Result<(), String> {
    let tmp = tempfile::tempdir().expect("tempdir");
    let logs = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path();
    let d = dir.to_str().expect("utf8");
    std::fs::write(dir.join("scene.toml"), &case.scene).expect("write scene");
    case.extra.iter().for_each(|e| make(dir, e));
    let before = names_in(dir);
    let scene_arg = match &case.scene_arg {
        Some(a) => a.replace("{dir}", d),
        None => dir.join("scene.toml").to_string_lossy().into_owned(),
    };
    let mut args = vec!["render".to_string(), scene_arg, "-q".to_string()];
    if case.output {
        args.extend(["-o".to_string(), format!("{d}/out.exr")]);
    }
    args.extend(case.args.iter().map(|a| a.replace("{dir}", d)));
    if let Some(c) = &case.command {
        args = c.iter().map(|a| a.replace("{dir}", d)).collect();
    }
    let r = run_bounded(dir, logs.path(), &args, case.address_space_kb)?;
    let e = &r.stderr;
    let shown = || {
        format!(
            "stderr ({} bytes): {}",
            e.len(),
            e.chars().take(1500).collect::<String>()
        )
    };
    if r.ok {
        return Err(format!("exited 0; {}", shown()));
    }
    for want in &case.expect {
        let want = want.replace("{dir}", d);
        if !e.contains(&want) {
            return Err(format!("missing {want:?}; {}", shown()));
        }
    }
    if let Some(bad) = case.refuse.iter().find(|r| e.contains(r.as_str())) {
        return Err(format!("says {bad:?}; {}", shown()));
    }
    if let Some(c) = e.chars().find(|c| c.is_control() && *c != '\n') {
        return Err(format!(
            "raw control character {c:?} on the terminal; {}",
            shown()
        ));
    }
    if e.len() > 20_000 {
        return Err(format!("{} bytes of error", e.len()));
    }
    let after = names_in(dir);
    if after != before {
        return Err(format!("left behind: {after:?} (before: {before:?})"));
    }
    Ok(())
}

/// Run a table of cases; report every failure at once.
fn run_all(cases: Vec<Case>) {
    let mut failures = Vec::new();
    for c in &cases {
        if let Err(e) = run(c) {
            failures.push(format!("{}: {e}", c.name));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} cases failed:\n\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n\n")
    );
}

/// A chain of `n` list definitions, `o0` the root, each instancing the next
/// (with a transform when `transformed`).
fn chain(n: usize, transformed: bool) -> String {
    let mut s = String::from(
        "[render]\nwidth = 8\nheight = 8\nroot = \"o0\"\nintegrator = \"normals\"\n[cameras.c]\nclass = \"pinhole\"\n",
    );
    for i in 0..n {
        let child = if transformed {
            format!(
                "{{ object = \"o{}\", transform = {{ translate = [0.1, 0, 0] }} }}",
                i + 1
            )
        } else {
            format!("\"o{}\"", i + 1)
        };
        s.push_str(&format!(
            "[objects.o{i}]\nclass = \"list\"\nchildren = [{child}]\n"
        ));
    }
    s.push_str(&format!("[objects.o{n}]\nclass = \"sphere\"\n"));
    s
}

/// Class 1: Syntax, types, unknown keys, references, cycles, DAG depth.
fn structure_cases() -> Vec<Case> {
    vec![
        edit("unterminated_string", "root = \"world\"", "root = \"world", &["scene.toml:4:", "TOML syntax error"]),
        edit("duplicate_key", "height = 8", "height = 8\nheight = 9", &["scene.toml:4:1", "TOML syntax error", "duplicate key"]),
        scene("duplicate_table", format!("{GOOD}[objects.ball]\nclass = \"sphere\"\n"), &["scene.toml:32:", "TOML syntax error", "duplicate"]),
        edit("integer_beyond_64_bits", "width = 8", "width = 99999999999999999999", &["scene.toml:2:9", "the integer 99999999999999999999 is out of range", "between -9223372036854775808 and 9223372036854775807"]).refuse(&["i128", "TOML syntax error"]),
        edit("negative_integer_beyond_64_bits", "radius = 1.0", "radius = -9223372036854775809", &["scene.toml:23:10", "the integer -9223372036854775809 is out of range"]).refuse(&["i128"]),
        edit("nesting_too_deep", "width = 8", &format!("width = {}{}", "[".repeat(300), "]".repeat(300)), &["scene.toml:2:", "nested too deeply"]),
        // A table header 10,000 keys deep: the error is at its line, in the
        // scene and in a file it includes.
        edit("header_nested_too_deep", "[objects.tri]", &format!("[{}x]\nk = 1\n[objects.tri]", "x.".repeat(10_000)), &["scene.toml:25:1: TOML syntax error: values are nested too deeply"]),
        scene("header_nested_too_deep_in_an_include", format!("include = \"deep.toml\"\n{GOOD}"), &["deep.toml:3:1: TOML syntax error: values are nested too deeply"])
            .with(Extra::Bytes("deep.toml", format!("[shaders.s]\nclass = \"flat\"\n[{}x]\nk = 1\n", "x.".repeat(10_000)).into_bytes())),
        scene("empty_file", "", &["scene.toml", "missing section [render]"]),
        scene("render_not_a_table", "render = 5\n", &["scene.toml:1:10", "render: expected a table, found an integer"]),
        scene("section_not_a_table", "objects = 3\n[render]\nroot = \"x\"\n", &["scene.toml:1:11: objects: expected a table, found an integer"]),
        edit("unknown_section", "[objects.tri]", "[object.tri]", &["scene.toml:25:2", "key `object`", "unknown key; expected one of: render, cameras, lights, shaders, objects"]),
        edit("class_missing", "class = \"sphere\"\n", "", &["scene.toml:20:", "objects.ball: key `class`: missing key `class` (the plugin to use)"]),
        edit("class_is_a_path", "class = \"sphere\"", "class = \"../../tmp/evil\"", &["scene.toml:21:9", "objects.ball: key `class`", "is not a class name", "never a path"]),
        edit("class_unknown", "class = \"sphere\"", "class = \"spheer\"", &["scene.toml:21:9", "objects.ball: key `class`", "unknown class `spheer`", "classes found there:"]),
        edit("class_of_the_wrong_kind", "class = \"pinhole\"", "class = \"sphere\"", &["scene.toml:8:9", "cameras.main: key `class`", "class `sphere` is an object plugin, but a camera is needed here"]),
        edit("children_not_an_array", "children = [{ object = \"ball\", shader = \"red\" }, { object = \"tri\" }]", "children = \"ball\"", &["scene.toml:31:12", "objects.world: key `children`", "expected an array of instances, found a string"]),
        edit("instance_without_object", "{ object = \"tri\" }", "{ shader = \"red\" }", &["scene.toml:31:", "objects.world.children[1]: key `object`", "missing key `object`"]),
        edit("instance_unknown_key", "{ object = \"tri\" }", "{ object = \"tri\", shade = \"red\" }", &["scene.toml:31:", "objects.world.children[1]: key `shade`", "unknown key; expected one of: object, shader, transform, attributes"]),
        edit("instance_of_the_wrong_type", "{ object = \"tri\" }", "5", &["scene.toml:31:", "objects.world.children[1]", "an instance is an object name or a table { object = ... }, found an integer"]),
        edit("attributes_without_shader", "{ object = \"tri\" }", "{ object = \"tri\", attributes = { albedo = [1, 0, 0] } }", &["scene.toml:31:", "key `attributes`", "bind a `shader` too"]),
        edit("attributes_change_the_class", "shader = \"red\" }", "shader = \"red\", attributes = { class = \"flat\" } }", &["scene.toml:31:", "key `attributes.class`", "attributes cannot change the shader's class"]),
        edit("camera_unknown", "root = \"world\"", "root = \"world\"\ncamera = \"side\"", &["scene.toml:5:10", "render: key `camera`", "no camera named `side`", "cameras defined: main"]),
        edit("root_unknown", "root = \"world\"", "root = \"wrld\"", &["scene.toml:4:8", "render.root: key `object`", "no object named `wrld`", "objects defined: ball, tri, world"]),
        edit("self_cycle", "{ object = \"tri\" }", "\"world\"", &["scene.toml:31:", "objects.world.children[1]: key `object`", "instancing cycle: world -> world"]),
        scene("long_cycle", chain(40, false).replacen("[objects.o40]\nclass = \"sphere\"\n", "[objects.o40]\nclass = \"list\"\nchildren = [\"o3\"]\n", 1), &["key `object`", "the object DAG is more than 32 levels deep here"]),
        scene("short_cycle", chain(3, false).replacen("[objects.o3]\nclass = \"sphere\"\n", "[objects.o3]\nclass = \"list\"\nchildren = [\"o1\"]\n", 1), &["objects.o3.children[0]: key `object`", "instancing cycle: o1 -> o2 -> o3 -> o1"]),
        scene("dag_33_levels", chain(32, false), &["scene.toml:", "objects.o31.children[0]: key `object`", "the object DAG is more than 32 levels deep here (transforms count as a level); rtk traces at most 32"]),
        scene("dag_deep_through_transforms", chain(16, true), &["objects.o15.children[0]", "more than 32 levels deep here (transforms count as a level)"]),
        edit("mesh_without_file", "file = \"tri.obj\"\n", "", &["scene.toml:26:9", "objects.tri", "plugin `mesh` refused its parameters: missing key `file`"]).refuse(&["missing field"]),
        edit("enum_variant_unknown", "file = \"tri.obj\"", "file = \"tri.obj\"\nnormals = \"smooth\"", &["scene.toml:28:11", "objects.tri: key `normals`", "unknown variant `smooth`, expected one of `auto`, `face`, `vertex`"]),
        edit("accel_on_a_sphere", "radius = 1.0", "radius = 1.0\naccel = \"bvh\"", &["scene.toml:24:9", "objects.ball: key `accel`", "class `sphere` has no primitives"]),
        edit("accel_not_a_class", "file = \"tri.obj\"", "file = \"tri.obj\"\naccel = \"/usr/lib/evil\"", &["scene.toml:28:9", "objects.tri: key `accel`", "is not a class name"]),
        edit("integrator_without_class", "integrator = \"normals\"", "integrator = { max_depth = 3 }", &["scene.toml:5:14", "render.integrator: key `class`", "missing key `class`"]),
    ]
}

/// Class 2: Numbers finite in f64 but beyond f32, or beyond what f32 tracing handles.
fn number_cases() -> Vec<Case> {
    vec![
        edit("background_1e308", "width = 8", "width = 8\nbackground = [1e308, 0, 0]", &["scene.toml:3:15", "render: key `background[0]`", "1e308 is too large: radiance must be at most 1e12"]),
        edit("background_1e39", "width = 8", "width = 8\nbackground = [0, 1e39, 0]", &["scene.toml:3:18", "key `background[1]`", "1e39 is too large"]),
        edit("background_negative", "width = 8", "width = 8\nbackground = [0, 0, -1]", &["scene.toml:3:21", "key `background[2]`", "must not be negative"]),
        edit("background_two_numbers", "width = 8", "width = 8\nbackground = [0, 0]", &["scene.toml:3:14", "key `background`", "expected [r, g, b]"]),
        edit("radius_1e39", "radius = 1.0", "radius = 1e39", &["scene.toml:23:10", "objects.ball: key `radius`", "1e39 is too large: rtk computes in f32"]).refuse(&["inf"]),
        edit("intensity_1e39", "intensity = [10.0, 10.0, 10.0]", "intensity = [1e39, 10.0, 10.0]", &["scene.toml:14:14", "lights.sun: key `intensity[0]`", "1e39 is too large"]),
        edit("intensity_1e20", "intensity = [10.0, 10.0, 10.0]", "intensity = [10.0, 1e20, 10.0]", &["scene.toml:14:13", "lights.sun: key `intensity`", "plugin `point` refused its parameters", "beyond what f32 intersection handles (|x| <= 1e12)"]),
        edit("center_1e13", "center = [0.0, 0.0, 0.0]", "center = [1e13, 0.0, 0.0]", &["scene.toml:22:10", "objects.ball: key `center`", "beyond what f32 intersection handles"]),
        edit("eye_1e39", "eye = [0.0, 0.0, 5.0]", "eye = [0.0, 0.0, -1e39]", &["scene.toml:9:18", "cameras.main: key `eye[2]`", "-1e39 is too large"]),
        edit("albedo_1e39", "albedo = [0.8, 0.1, 0.1]", "albedo = [0.8, 1e39, 0.1]", &["scene.toml:18:16", "shaders.red: key `albedo[1]`", "1e39 is too large"]),
        edit("translation_1e20", "{ object = \"tri\" }", "{ object = \"tri\", transform = [{ translate = [1e20, 0, 0] }] }", &["scene.toml:31:", "objects.world.children[1]: key `transform[0].translate`", "moves the instance by 1e20 along x, beyond ±1e12"]),
        edit("translation_composed_beyond", "{ object = \"tri\" }", "{ object = \"tri\", transform = [{ translate = [0, 0, 1e7] }, { scale = 1e6 }] }", &["key `transform[1].scale`", "moves the instance by 1e13 along z"]),
        edit("matrix_translation_1e15", "{ object = \"tri\" }", "{ object = \"tri\", transform = { matrix = [1, 0, 0, 0, 0, 1, 0, 1e15, 0, 0, 1, 0] } }", &["key `transform[0].matrix`", "moves the instance by 1e15 along y"]),
        edit("scale_1e39", "{ object = \"tri\" }", "{ object = \"tri\", transform = [{ scale = 1e39 }] }", &["key `transform[0].scale`", "1e39 is too large"]),
        edit("scale_1e20", "{ object = \"tri\" }", "{ object = \"tri\", transform = [{ scale = 1e20 }] }", &["key `transform[0].scale`", "scales by more than 1e12"]),
        edit("scale_1e-20", "{ object = \"tri\" }", "{ object = \"tri\", transform = [{ scale = 1e-20 }] }", &["key `transform[0].scale`", "scales by less than 1e-12"]),
        edit("width_zero", "width = 8", "width = 0", &["scene.toml:2:9", "render: key `width`", "must be between 1 and 65536, got 0"]),
        edit("seed_negative", "width = 8", "width = 8\nseed = -1", &["scene.toml:3:8", "key `seed`", "must be between 0 and"]),
        edit("max_depth_negative", "integrator = \"normals\"", "integrator = { class = \"whitted\", max_depth = -1 }", &["scene.toml:5:47", "render.integrator: key `max_depth`", "the integer -1 is out of range: expected a whole number from 0 to 4294967295"]).refuse(&["u32"]),
        edit("max_depth_fraction", "integrator = \"normals\"", "integrator = { class = \"whitted\", max_depth = 1.5 }", &["key `max_depth`", "expected a whole number from 0 to 4294967295, found the number 1.5"]).refuse(&["u32", "floating point"]),
        edit("max_depth_beyond_u32", "integrator = \"normals\"", "integrator = { class = \"whitted\", max_depth = 5000000000 }", &["key `max_depth`", "the integer 5000000000 is out of range"]).refuse(&["u32"]),
        edit("fov_a_string", "eye = [0.0, 0.0, 5.0]", "eye = [0.0, 0.0, 5.0]\nfov_y = \"wide\"", &["scene.toml:10:9", "cameras.main: key `fov_y`", "expected a number, found the string \"wide\""]).refuse(&["f32"]),
        edit("eye_four_numbers", "eye = [0.0, 0.0, 5.0]", "eye = [0.0, 0.0, 5.0, 1.0]", &["scene.toml:9:7", "key `eye`", "the array has too many elements"]).refuse(&["trailing characters"]),
        edit("transform_step_an_empty_array", "{ object = \"tri\" }", "{ object = \"tri\", transform = [[]] }", &["key `transform[0]`", "expected a table, found 0 elements"]).refuse(&["struct", "Step"]),
        edit("transform_scale_a_string", "{ object = \"tri\" }", "{ object = \"tri\", transform = [{ scale = \"x\" }] }", &["key `transform[0].scale`", "expected a number or an array [x, y, z]"]).refuse(&["untagged", "enum"]),
        edit("bvh_bound_an_integer", "class = \"list\"\nchildren", "class = \"bvh\"\nbound = 1\nchildren", &["scene.toml:31:9", "objects.world: key `bound`", "expected a string, one of the accepted names"]).refuse(&["expected value"]),
        edit("bvh_simd_misspelt", "class = \"list\"\nchildren", "class = \"bvh\"\nsimd = \"avx\"\nchildren", &["scene.toml:31:8", "objects.world: key `simd`", "avx512", "portable"]),
        edit("bvh_simd_on_a_4_wide_tree", "class = \"list\"\nchildren", "class = \"bvh\"\nwidth = 4\nsimd = \"portable\"\nchildren", &["objects.world: key `simd`", "a 4-wide one always runs SSE"]),
        edit("transform_rotate_a_number", "{ object = \"tri\" }", "{ object = \"tri\", transform = [{ rotate = 5 }] }", &["key `transform[0].rotate`", "expected a table, found the integer 5"]).refuse(&["AxisAngle"]),
    ]
}

/// Class 3: Sizes: the film, instances, a long chain.
fn size_cases() -> Vec<Case> {
    let many: Vec<&str> = vec!["\"ball\""; MAX_INSTANCES + 1];
    vec![
        edit(
            "film_cannot_be_allocated",
            "width = 8\nheight = 8",
            "width = 16384\nheight = 16384",
            &[
                "scene.toml: the film of 16384x16384 pixels needs 13312 MiB",
                "could not be allocated",
            ],
        )
        .address_space_kb(3 << 20),
        edit(
            "too_many_instances",
            "children = [{ object = \"ball\", shader = \"red\" }, { object = \"tri\" }]",
            &format!("children = [{}]", many.join(",")),
            &[
                "scene.toml:31:12",
                "objects.world: key `children`",
                "more than 1048576 instances, rtk's limit",
            ],
        ),
        scene(
            "chain_of_20000",
            chain(20_000, false),
            &[
                "objects.o31.children[0]: key `object`",
                "more than 32 levels deep",
            ],
        ),
        scene(
            "transformed_chain_of_20000",
            chain(20_000, true),
            &["objects.o15.children[0]", "more than 32 levels deep"],
        ),
    ]
}

/// The shell's instance limit (docs/scene-format.md, "Limits").
const MAX_INSTANCES: usize = 1 << 20;

const PLY_HEADER: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";

fn ply(body: &str) -> String {
    format!("{PLY_HEADER}{body}")
}

/// `text` in Latin-1: one byte a character, not UTF-8.
fn latin1(text: &str) -> Vec<u8> {
    text.chars().map(|c| c as u32 as u8).collect()
}

/// Class 4: Files: special files, sizes, broken and lying meshes.
fn file_cases() -> Vec<Case> {
    let mesh_key = [
        "scene.toml:27:8",
        "objects.tri: key `file`",
        "plugin `mesh` refused to build",
    ];
    let with_key = |c: Case| {
        let mut c = c;
        c.expect.extend(mesh_key.iter().map(|s| s.to_string()));
        c
    };
    let bvh = bin_dir()
        .join(format!(
            "{}rtk_bvh{}",
            std::env::consts::DLL_PREFIX,
            std::env::consts::DLL_SUFFIX
        ))
        .to_string_lossy()
        .into_owned();
    vec![
        scene("scene_is_a_fifo", "", &["pipe.toml: cannot read the scene file: it is a FIFO, not a regular file"]).with(Extra::Fifo("pipe.toml")).scene_arg("{dir}/pipe.toml"),
        scene("scene_is_dev_zero", "", &["/dev/zero: cannot read the scene file: it is a device, not a regular file"]).scene_arg("/dev/zero"),
        scene("scene_links_to_dev_zero", "", &["zero.toml: cannot read the scene file: it is a device"]).with(Extra::Link("zero.toml", "/dev/zero")).scene_arg("{dir}/zero.toml"),
        scene("scene_is_a_folder", "", &["folder.toml: cannot read the scene file: it is a folder"]).with(Extra::Dir("folder.toml")).scene_arg("{dir}/folder.toml"),
        scene("scene_over_64_mib", "", &["huge.toml: the scene file is 67108865 bytes, more than rtk's limit of 64 MiB"]).with(Extra::Sparse("huge.toml", (64 << 20) + 1)).scene_arg("{dir}/huge.toml"),
        scene("scene_missing", "", &["none.toml: cannot read the scene file: No such file"]).scene_arg("{dir}/none.toml"),
        scene("scene_not_utf8", GOOD, &["scene.toml:3:17: the scene file is not UTF-8 text (byte 0xE9)"]).with(Extra::Bytes("scene.toml", latin1(&GOOD.replacen("height = 8", "height = 8 # caf\u{e9}", 1)))),
        with_key(edit("mesh_is_a_fifo", "file = \"tri.obj\"", "file = \"pipe.obj\"", &["pipe.obj: cannot read the mesh file: it is a FIFO, not a regular file"]).with(Extra::Fifo("pipe.obj"))),
        with_key(edit("mesh_links_to_dev_zero", "file = \"tri.obj\"", "file = \"zero.obj\"", &["zero.obj: cannot read the mesh file: it is a device"]).with(Extra::Link("zero.obj", "/dev/zero"))),
        with_key(edit("mesh_is_a_folder", "file = \"tri.obj\"", "file = \"sub.obj\"", &["sub.obj: cannot read the mesh file: it is a folder"]).with(Extra::Dir("sub.obj"))),
        with_key(edit("mesh_over_2_gib", "file = \"tri.obj\"", "file = \"huge.ply\"", &["huge.ply: the mesh file is 2147483649 bytes, more than rtk's limit of 2 GiB for a mesh"]).with(Extra::Sparse("huge.ply", (2 << 30) + 1))),
        with_key(edit("mesh_missing", "file = \"tri.obj\"", "file = \"gone.obj\"", &["gone.obj: cannot read the mesh file: No such file"])),
        mesh("mesh_unknown_format", "tri.stl", b"solid x\n", &["scene.toml:27:8", "objects.tri: key `file`: plugin `mesh` refused its parameters: tri.stl: unknown mesh format: use .ply or .obj"]),
        with_key(mesh("ply_truncated", "t.ply", ply("0 0 0\n1 0 0\n0 1 0\n").as_bytes(), &["t.ply: the header declares 1 `face` elements, which need at least 20 bytes, but 18 bytes follow the header: the file is truncated or its counts are wrong"])),
        with_key(mesh("ply_lying_vertex_count", "l.ply", ply("0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").replacen("element vertex 3", "element vertex 3000000000", 1).as_bytes(), &["l.ply: the header declares 3000000000 `vertex` elements", "truncated or its counts are wrong"])),
        with_key(mesh("ply_lying_binary_count", "b.ply", b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\0\0\0\0", &["b.ply: the header declares 4000000000 `vertex` elements, which need at least 48000000000 bytes, but 4 bytes follow"])),
        with_key(mesh("ply_element_without_properties", "n.ply", b"ply\nformat binary_little_endian 1.0\nelement vertex 2000000000\nend_header\n", &["n.ply: the header declares 2000000000 `vertex` elements but no property for them"])),
        with_key(mesh("ply_index_out_of_range", "o.ply", ply("0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n").as_bytes(), &["o.ply: triangle 0 refers to vertex [0, 1, 7], but there are 3 vertices"])),
        with_key(mesh("ply_negative_index", "g.ply", ply("0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n").as_bytes(), &["g.ply: face 0 has the vertex index -1, which cannot be one"])),
        with_key(mesh("ply_face_of_two_vertices", "w.ply", ply("0 0 0\n1 0 0\n0 1 0\n2 0 1\n").as_bytes(), &["w.ply: face 0 has 2 vertices; a face needs at least 3"])),
        with_key(mesh("ply_header_unterminated", "h.ply", b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n", &["h.ply: not a readable PLY file: Line 5", "missing 'end_header'"])),
        with_key(mesh("ply_list_count_lies", "c.ply", ply("0 0 0\n1 0 0\n0 1 0\n200 0 1 2\n").as_bytes(), &["c.ply: not a readable PLY file: Line 13", "Expected 200 list elements, but found only 3"])),
        with_key(mesh("ply_coordinate_1e39", "f.ply", ply("0 0 0\n1 0 0\n0 1 1e39\n3 0 1 2\n").as_bytes(), &["f.ply: vertex 2 has a non-finite or out-of-range coordinate"])),
        with_key(mesh("obj_not_utf8", "u.obj", b"v 0 0 0\nv 1 \xff 0\nv 0 1 0\nf 1 2 3\n", &["u.obj: line 2: not UTF-8 text (byte 0xFF)"])),
        with_key(mesh("obj_face_of_two_vertices", "w.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2\n", &["w.obj: line 5: a face needs at least 3 vertices, found 2"])),
        with_key(mesh("obj_index_out_of_range", "o.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", &["o.obj: line 4: vertex index 9 is out of range: the file has 3 vertices"])),
        with_key(mesh("obj_relative_index_out_of_range", "r.obj", b"v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n", &["r.obj: line 3: vertex index -3 is out of range: only 2 vertices come before this line"])),
        with_key(mesh("obj_index_zero", "z.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", &["z.obj: line 4: vertex index 0 is out of range: OBJ indices start at 1"])),
        with_key(mesh("obj_not_a_number", "n.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 abc\nf 1 2 3\n", &["n.obj: line 3: `abc` is not a number"])),
        with_key(mesh("obj_vertex_of_two_numbers", "v.obj", b"v 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", &["v.obj: line 1: a vertex needs 3 numbers, found 2"])),
        with_key(mesh("obj_no_triangles", "e.obj", b"# nothing\nv 0 0 0\n", &["e.obj: the mesh has no triangles"])),
        scene("trace_iters_beyond_the_limit", GOOD, &["--iters must be at most 1000, got 100000"]).command(&["trace", "{dir}/tri.obj", "--rayset", "primary", "--iters", "100000"]),
        edit("raycls_negative_max_candidates", "class = \"list\"", "class = \"raycls\"\nmax_candidates = -1", &["scene.toml:", "objects.world: key `max_candidates`", "must be between 1 and 1048576"]).refuse(&["4294967295"]),
        scene("trace_rays_from_a_fifo", GOOD, &["rays.bin: cannot read the ray file: it is a FIFO, not a regular file"]).with(Extra::Fifo("rays.bin")).command(&["trace", "{dir}/tri.obj", "--rays", "{dir}/rays.bin"]),
        scene("trace_rays_from_dev_zero", GOOD, &["/dev/zero: cannot read the ray file: it is a device"]).command(&["trace", "{dir}/tri.obj", "--rays", "/dev/zero"]),
        scene("trace_set_render_origin", GOOD, &["--set render.origin=camera: rtk trace traces in world coordinates", "render.origin cannot be set"]).command(&["trace", "{dir}/tri.obj", "--rayset", "primary", "--set", "render.origin=camera"]),
        scene("trace_set_a_misspelt_key", GOOD, &["objects.world: key `simdd`", "unknown field"]).command(&["trace", "{dir}/tri.obj", "--rayset", "primary", "--set", "objects.world.simdd=avx2"]),
        scene("trace_iters_zero", GOOD, &["--iters must be at least 1"]).command(&["trace", "{dir}/tri.obj", "--rayset", "primary", "--iters", "0"]),
        scene("trace_scene_from_a_fifo", GOOD, &["pipe.toml: cannot read the scene file: it is a FIFO"]).with(Extra::Fifo("pipe.toml")).command(&["trace", "{dir}/pipe.toml", "--rayset", "primary"]),
        scene("trace_mesh_from_a_fifo", GOOD, &["objects.mesh: key `file`", "pipe.ply: cannot read the mesh file: it is a FIFO"]).with(Extra::Fifo("pipe.ply")).command(&["trace", "{dir}/pipe.ply", "--rayset", "primary"]),
        edit("bicubic_file_is_a_fifo", "class = \"mesh\"\nfile = \"tri.obj\"", "class = \"bicubic\"\nfile = \"pipe.bpt\"", &["scene.toml:27:8", "objects.tri: key `file`: plugin `bicubic` refused to build", "pipe.bpt: it is a FIFO, not a regular file"]).with(Extra::Fifo("pipe.bpt")),
        edit("bicubic_file_is_dev_zero", "class = \"mesh\"\nfile = \"tri.obj\"", "class = \"bicubic\"\nfile = \"/dev/zero\"", &["scene.toml:27:8", "objects.tri: key `file`", "cannot read /dev/zero: it is a device, not a regular file"]),
        scene("merge_film_header_of_huge_size", GOOD, &["huge.rtkfilm: a damaged film header (image 4294967295x4294967295, 1 spp, rectangle 0,0,1,1)"]).with(Extra::Bytes("huge.rtkfilm", film(u32::MAX, u32::MAX, 1, f64::INFINITY))).command(&["merge", "{dir}/out.exr", "{dir}/huge.rtkfilm"]).refuse(&["panicked", "capacity overflow"]),
        scene("merge_film_spp_zero", GOOD, &["z.rtkfilm: a damaged film header (image 1x1, 0 spp, rectangle 0,0,1,1)"]).with(Extra::Bytes("z.rtkfilm", film(1, 1, 0, 0.0))).command(&["merge", "{dir}/out.exr", "{dir}/z.rtkfilm"]),
        scene("merge_film_of_version_1", GOOD, &["v1.rtkfilm is a film file of version 1", "this rtk reads version 2 only"]).with(Extra::Bytes("v1.rtkfilm", [b"RTKFILM1".as_slice(), &film(1, 1, 1, 0.5)[8..]].concat())).command(&["merge", "{dir}/out.exr", "{dir}/v1.rtkfilm"]),
        scene("merge_film_with_a_negative_square", GOOD, &["neg.rtkfilm: a pixel's sum of squares is not a finite non-negative number: damaged"]).with(Extra::Bytes("neg.rtkfilm", { let mut f = film(1, 1, 1, 0.5); let n = f.len(); f[n - 12..n - 4].copy_from_slice(&(-1.0f64).to_le_bytes()); f })).command(&["merge", "{dir}/out.exr", "{dir}/neg.rtkfilm"]),
        scene("merge_film_with_a_nan_sum", GOOD, &["nan.rtkfilm: a pixel's sum is not a finite number: damaged"]).with(Extra::Bytes("nan.rtkfilm", film(1, 1, 1, f64::NAN))).command(&["merge", "{dir}/out.exr", "{dir}/nan.rtkfilm"]),
        scene("resume_film_header_of_huge_size", GOOD, &["huge.rtkfilm: a damaged film header (image 4294967295x4294967295"]).with(Extra::Bytes("huge.rtkfilm", film(u32::MAX, u32::MAX, 1, 0.0))).args(&["--resume", "{dir}/huge.rtkfilm"]).refuse(&["panicked"]),
        scene("conform_params_from_dev_zero", GOOD, &["--params @/dev/zero: cannot read the parameter file: it is a device, not a regular file"]).command(&["conform", &bvh, "--params", "@/dev/zero"]),
        scene("conform_params_from_a_fifo", GOOD, &["p.toml: cannot read the parameter file: it is a FIFO, not a regular file"]).with(Extra::Fifo("p.toml")).command(&["conform", &bvh, "--params", "@{dir}/p.toml"]),
        scene("conform_params_file_malformed", GOOD, &["--params @{dir}/p.toml: not a TOML table", "line 1, column 9"]).with(Extra::Bytes("p.toml", b"width = \n".to_vec())).command(&["conform", &bvh, "--params", "@{dir}/p.toml"]),
        scene("conform_misspelt_oracle", GOOD, &["--oracle: unknown class `lsit`: no librtk_lsit.so on the plugin path"]).command(&["conform", &bvh, "--oracle", "lsit", "--quick"]).refuse(&["FAIL", "fails"]),
        scene("conform_plugin_is_a_fifo", GOOD, &["librtk_pipe.so: not a regular file"]).with(Extra::Fifo("librtk_pipe.so")).command(&["conform", "{dir}/librtk_pipe.so", "--class", "pipe"]),
        scene("conform_plugin_missing", GOOD, &["librtk_nope.so: No such file"]).command(&["conform", "{dir}/librtk_nope.so"]).refuse(&["cannot tell the class"]),
        scene("conform_plugin_not_a_library", GOOD, &["p.so: cannot load {dir}/p.so: "]).with(Extra::Bytes("p.so", b"root:x:0:0\n".to_vec())).command(&["conform", "{dir}/p.so", "--class", "p"]).refuse(&["dlopen failed"]),
        with_key(mesh("obj_escape_in_file", "x.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 \x1b[2J\n", &["x.obj: line 4: `\\u{1b}[2J` is not a vertex index"])),
    ]
}

/// A film file (docs/farm.md) of a `w` x `h` image holding its pixel
/// (0, 0) alone, with `sum` in each channel (its square the sums of
/// squares) and one sample.
fn film(w: u32, h: u32, spp: u32, sum: f64) -> Vec<u8> {
    let mut b = b"RTKFILM2".to_vec();
    b.extend(0u64.to_le_bytes());
    for v in [w, h, spp] {
        b.extend(v.to_le_bytes());
    }
    b.extend(0u64.to_le_bytes());
    for v in [0u32, 0, 0, 0, 1, 1] {
        b.extend(v.to_le_bytes());
    }
    for _ in 0..3 {
        b.extend(sum.to_le_bytes());
    }
    for _ in 0..3 {
        b.extend((sum * sum).to_le_bytes());
    }
    b.extend(1u32.to_le_bytes());
    b
}

/// Class 5: Messages: `--set`, terminal escapes, huge keys, the output checked
/// before rendering.
fn message_cases() -> Vec<Case> {
    let huge = "k".repeat(10 << 20);
    vec![
        edit("set_unclosed_array", "width = 8", "width = 8", &["scene.toml (from --set render.width=[1,2): key `render.width`: `[1,2` is not a TOML value", "unclosed array"]).args(&["--set", "render.width=[1,2"]),
        edit("set_not_a_number", "width = 8", "width = 8", &["key `render.width`: `2x` is not a TOML value", "write strings other than bare words in quotes"]).args(&["--set", "render.width=2x"]),
        edit("set_bare_word_is_a_string", "width = 8", "width = 8", &["(from --set render.camera=side): render: key `camera`: no camera named `side`"]).args(&["--set", "render.camera=side"]),
        edit("set_integer_beyond_64_bits", "width = 8", "width = 8", &["key `render.spp`: the integer 99999999999999999999 is out of range"]).args(&["--set", "render.spp=99999999999999999999"]).refuse(&["i128", "expected an integer, found a string"]),
        edit("set_undefined_object", "width = 8", "width = 8", &["(from --set objects.bal.radius=2): objects.bal: the scene defines no `bal` in [objects]", "objects defined: ball, tri, world"]).args(&["--set", "objects.bal.radius=2"]).refuse(&["missing key `class`"]),
        edit("set_undefined_light", "width = 8", "width = 8", &["lights.moon: the scene defines no `moon` in [lights]", "a new definition needs its `class` set first", "lights defined: sun"]).args(&["--set", "lights.moon.intensity=[1,1,1]"]),
        edit("set_new_definition_class_first", "width = 8", "width = 8", &["(from --set objects.extra.radius=-2): objects.extra: key `radius`: plugin `sphere` refused its parameters", "must be a positive number"]).args(&["--set", "objects.extra.class=sphere", "--set", "objects.extra.radius=-2", "--set", "render.root=extra"]),
        edit("set_unknown_section", "width = 8", "width = 8", &["key `scene.width`: the key path must start with one of render, cameras, lights, shaders, objects"]).args(&["--set", "scene.width=3"]),
        edit("set_without_value", "width = 8", "width = 8", &["(from --set render.width): expected --set key.path=value"]).args(&["--set", "render.width"]),
        edit("set_inside_a_number", "width = 8", "width = 8", &["key `render.width.x`: `x` is inside an integer, not a table"]).args(&["--set", "render.width.x=1"]),
        edit("set_empty_value", "width = 8", "width = 8", &["key `render.width`: the value is empty"]).args(&["--set", "render.width="]),
        edit("escape_in_key", "width = 8", "width = 8\n\"\\u001b[2J\\u001b]0;pwned\\u0007\" = 1", &["scene.toml:3:1", "render: key `\\u{1b}[2J\\u{1b}]0;pwned\\u{7}`: unknown key"]),
        edit("escape_in_class", "class = \"sphere\"", "class = \"\\u001b[31mred\"", &["objects.ball: key `class`: `\\u{1b}[31mred` is not a class name"]),
        edit("escape_in_object_name", "[objects.tri]", "[objects.\"\\u001b[1m\"]", &["no object named `tri`", "objects defined: \\u{1b}[1m, ball, world"]),
        edit("escape_in_output", "width = 8", "width = 8\noutput = \"\\u001b[31mx.jpg\"", &["output \\u{1b}[31mx.jpg: the file name must end in .png or .exr"]).no_output(),
        edit("escape_in_mesh_path", "file = \"tri.obj\"", "file = \"\\u001b[2J.obj\"", &["scene.toml:27:8", "\\u{1b}[2J.obj: cannot read the mesh file"]),
        edit("huge_key", "width = 8", &format!("width = 8\n\"{huge}\" = 1"), &["scene.toml:3:1", "render: key `kkkkkkkkkk", "…`: unknown key"]),
        edit("huge_plugin_key", "radius = 1.0", &format!("radius = 1.0\n{} = 1", &huge[..1 << 20]), &["scene.toml:24:1", "objects.ball: key `kkkkkkkk", "unknown field `kkkkkkkk", "…`"]),
        edit("huge_class", "class = \"sphere\"", &format!("class = \"{huge}-x\""), &["objects.ball: key `class`: `kkkkkk", "…` is not a class name"]),
        edit("output_unwritable_found_before_rendering", "width = 8", "width = 8", &["output /proc/rtk-hostile.png: cannot write in the folder /proc"]).args(&["-o", "/proc/rtk-hostile.png", "--spp", "1000000", "--set", "render.width=4096", "--set", "render.height=4096"]).no_output(),
        edit("output_is_a_folder", "width = 8", "width = 8", &["output {dir}/sub.png: is a folder"]).with(Extra::Dir("sub.png")).args(&["-o", "{dir}/sub.png"]).no_output(),
        edit("output_folder_missing", "width = 8", "width = 8", &["output {dir}/no/x.png: the folder {dir}/no does not exist"]).args(&["-o", "{dir}/no/x.png"]).no_output(),
        edit("threads_beyond_the_limit", "width = 8", "width = 8", &["--threads must be at most 1024, got 100000"]).args(&["--threads", "100000"]),
        scene("bench_aggregate_zero_rays", GOOD, &["--rays must be at least 1"]).command(&["bench-aggregate", "bvh", "--mesh", "{dir}/tri.obj", "--rays", "0"]),
        scene("converge_negative_constant_reference", GOOD, &["--analytic `constant:-1`: the colour must not be negative"]).command(&["converge", "{dir}/scene.toml", "--analytic", "constant:-1", "--out", "{dir}/cv"]),
        edit("output_without_format", "width = 8", "width = 8\noutput = \"picture\"", &["output picture: the file name must end in .png or .exr"]).no_output(),
    ]
}

/// Class 6: Trust: `--safe` keeps a scene's files inside its folder or the
/// working directory.
fn trust_cases() -> Vec<Case> {
    vec![
        edit("safe_absolute_output", "width = 8", "width = 8\noutput = \"/tmp/rtk-hostile.png\"", &["scene.toml:3:10", "render: key `output`: --safe: the scene names an absolute output path `/tmp/rtk-hostile.png`"]).args(&["--safe"]).no_output(),
        edit("safe_output_outside", "width = 8", "width = 8\noutput = \"../rtk-hostile.png\"", &["scene.toml:3:10", "render: key `output`: --safe: `../rtk-hostile.png` is outside the scene's folder"]).args(&["--safe"]).no_output(),
        edit("safe_absolute_mesh", "file = \"tri.obj\"", "file = \"/etc/rtk-hostile.obj\"", &["scene.toml:27:8", "objects.tri: key `file`: --safe: `/etc/rtk-hostile.obj` is outside the scene's folder", "and the working directory"]).args(&["--safe"]),
        edit("safe_mesh_up_the_tree", "file = \"tri.obj\"", "file = \"../../../../../../etc/hostname.obj\"", &["scene.toml:27:8", "key `file`: --safe: `../../../../../../etc/hostname.obj` is outside"]).args(&["--safe"]),
        edit("safe_mesh_through_a_link", "file = \"tri.obj\"", "file = \"out/tri.obj\"", &["scene.toml:27:8", "key `file`: --safe: `out/tri.obj` is outside"]).with(Extra::Link("out", "/etc")).args(&["--safe"]),
        edit("safe_file_in_attributes", "shader = \"red\" }", "shader = \"red\", attributes = { texture_file = \"/etc/passwd\" } }", &["scene.toml:31:", "objects.world.children[0]: key `attributes.texture_file`: --safe: `/etc/passwd` is outside"]).args(&["--safe"]),
        edit("safe_nested_file", "albedo = [0.8, 0.1, 0.1]", "albedo = [0.8, 0.1, 0.1]\nmap = { file = \"/etc/passwd\" }", &["scene.toml:19:", "shaders.red: key `map.file`: --safe: `/etc/passwd` is outside"]).args(&["--safe"]),
    ]
}

#[test]
fn structure() {
    run_all(structure_cases());
}

#[test]
fn numbers() {
    run_all(number_cases());
}

#[test]
fn sizes() {
    run_all(size_cases());
}

#[test]
fn files() {
    run_all(file_cases());
}

#[test]
fn messages() {
    run_all(message_cases());
}

#[test]
fn trust() {
    run_all(trust_cases());
}

#[test]
fn the_catalogue_has_at_least_sixty_cases_and_unique_names() {
    let all: Vec<Case> = [
        structure_cases(),
        number_cases(),
        size_cases(),
        file_cases(),
        message_cases(),
        trust_cases(),
    ]
    .into_iter()
    .flatten()
    .collect();
    assert!(all.len() >= 60, "{} cases", all.len());
    let mut names: Vec<&str> = all.iter().map(|c| c.name).collect();
    names.sort();
    let n = names.len();
    names.dedup();
    assert_eq!(n, names.len(), "case names repeat");
}

/// The good scene renders, with and without `--safe`: the catalogue's
/// failures are the edits', not the scene's.
#[test]
fn the_good_scene_renders_even_under_safe() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(dir.path().join("scene.toml"), GOOD).expect("write");
    std::fs::write(dir.path().join("tri.obj"), TRI_OBJ).expect("write");
    for args in [&[][..], &["--safe"][..]] {
        let (run, img) = render_file(&dir.path().join("scene.toml"), dir.path(), args);
        assert!(run.ok, "{args:?}: {}", run.stderr);
        assert!(img.is_some());
    }
}

/// `--safe` lets a scene write its output inside its folder or the working
/// directory (a relative path).
#[test]
fn safe_allows_a_relative_output_in_the_working_directory() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(dir.path().join("tri.obj"), TRI_OBJ).expect("write");
    let scene = GOOD.replacen("width = 8", "width = 8\noutput = \"sub/ok.png\"", 1);
    std::fs::write(dir.path().join("scene.toml"), scene).expect("write");
    std::fs::create_dir(dir.path().join("sub")).expect("mkdir");
    let run = Run::from(
        rtk(&["render", "scene.toml", "--safe", "-q"])
            .current_dir(dir.path())
            .output()
            .expect("run rtk"),
    );
    assert!(run.ok, "{}", run.stderr);
    assert!(dir.path().join("sub/ok.png").is_file());
}

/// A million transformed instances render (about 4.5 GB and half a minute:
/// run with `--ignored`); the limit above is refused by `too_many_instances`.
#[test]
#[ignore]
fn a_million_transformed_instances_render() {
    let children: Vec<String> = (0..1_000_000)
        .map(|i| {
            format!(
                "{{ object = \"ball\", transform = {{ translate = [{}, 0, 0] }} }}",
                i % 1000
            )
        })
        .collect();
    let scene = GOOD
        .replacen("integrator = \"normals\"", "integrator = \"normals\"\nwidth = 4\nheight = 4", 1)
        .replacen("width = 8\nheight = 8\n", "", 1)
        .replacen(
            "class = \"list\"\nchildren = [{ object = \"ball\", shader = \"red\" }, { object = \"tri\" }]",
            &format!("class = \"bvh\"\nchildren = [{}]", children.join(",\n")),
            1,
        );
    let (run, img) = render_scene(&scene, &["--stats"]);
    assert!(run.ok, "{}", run.stderr);
    assert!(img.is_some());
}

/// Under an address-space limit (`ulimit -v`, 4 GiB) too small for 64
/// threads' stacks, `--threads 64` renders with fewer threads, saying why
/// on stderr, and the image is the one-thread image (images do not depend
/// on the thread count).
#[test]
#[cfg(target_os = "linux")]
fn threads_beyond_the_address_space_limit_are_reduced_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let scene = root().join("scenes/sphere-normals.toml");
    let (one, many) = (dir.path().join("one.exr"), dir.path().join("many.exr"));
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let r = Run::from(
        rtk(&["render", &s(&scene), "-q", "--threads", "1", "-o", &s(&one)])
            .output()
            .unwrap(),
    );
    assert!(r.ok, "{}", r.stderr);
    let script = format!(
        "ulimit -v 4194304 && exec {} render {} -q --threads 64 -o {}",
        rtk_path().display(),
        s(&scene),
        s(&many)
    );
    let out = std::process::Command::new("sh")
        .args(["-c", &script])
        .env_remove("RTK_PLUGIN_PATH")
        .output()
        .unwrap();
    let r = Run::from(out);
    assert!(r.ok, "{}", r.stderr);
    assert!(
        r.stderr.contains("64 threads asked for, using ")
            && r.stderr
                .contains("address-space limit (ulimit -v, 4.0 GiB)"),
        "{}",
        r.stderr
    );
    assert!(
        std::fs::read(&one).unwrap() == std::fs::read(&many).unwrap(),
        "the image depends on the thread count"
    );
}

/// A run killed while writing leaves its temporary (`.NAME.PID.tmp`, beside
/// the target); the next run writing that target removes it, and leaves a
/// live process's temporary alone (a pid above Linux's largest is never
/// alive; the test's own is).
#[test]
#[cfg(target_os = "linux")]
fn a_killed_runs_temporary_is_removed_by_the_next_run() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.exr");
    let stale = dir.path().join(".out.exr.4194305.tmp");
    let live = dir
        .path()
        .join(format!(".out.exr.{}.tmp", std::process::id()));
    std::fs::write(&stale, b"half an image").unwrap();
    std::fs::write(&live, b"being written").unwrap();
    let scene = root().join("scenes/sphere-normals.toml");
    let r = Run::from(
        rtk(&[
            "render",
            scene.to_str().unwrap(),
            "-q",
            "-o",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap(),
    );
    assert!(r.ok, "{}", r.stderr);
    assert!(out.is_file());
    assert!(!stale.exists(), "the stale temporary is still there");
    assert!(live.exists(), "a live process's temporary was removed");
}

/// `rtk render` under a file-size limit of `blocks` KiB (RLIMIT_FSIZE via
/// the shell's `ulimit -f`, with SIGXFSZ ignored so that a write past it
/// fails with EFBIG, as on a full disk, instead of killing the process).
#[cfg(target_os = "linux")]
fn render_under_fsize_limit(blocks: u32, args: &[&str]) -> Run {
    let mut cmd = std::process::Command::new("bash");
    cmd.arg("-c")
        .arg(format!(
            "trap '' XFSZ; ulimit -f {blocks}; exec \"$0\" \"$@\""
        ))
        .arg(rtk_path())
        .args(args)
        .env_remove("RTK_PLUGIN_PATH")
        .env("RUST_BACKTRACE", "0");
    Run::from(cmd.output().unwrap())
}

/// A disk that fills while the output is written (issue 25, item 1): a
/// clear error naming the file, a non-zero exit, the previous output
/// intact, and no temporary left beside it.
#[test]
#[cfg(target_os = "linux")]
fn a_full_disk_while_writing_the_image_keeps_the_previous_one() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.exr");
    std::fs::write(&out, b"the previous image").unwrap();
    let scene = root().join("scenes/sphere-normals.toml");
    let r = render_under_fsize_limit(
        16,
        &[
            "render",
            scene.to_str().unwrap(),
            "-q",
            "-o",
            out.to_str().unwrap(),
        ],
    );
    assert!(!r.ok);
    assert!(
        r.stderr.contains("writing") && r.stderr.contains("out.exr"),
        "{}",
        r.stderr
    );
    assert!(
        r.stderr.contains("File too large") || r.stderr.contains("too large"),
        "{}",
        r.stderr
    );
    assert_eq!(std::fs::read(&out).unwrap(), b"the previous image");
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .flatten()
        .map(|e| e.file_name())
        .collect();
    assert_eq!(left.len(), 1, "left behind: {left:?}");
}

/// The same for a checkpoint: a checkpoint that cannot be written stops the
/// render with an error naming it, and the previous checkpoint still loads
/// (a resume from it completes the render).
#[test]
#[cfg(target_os = "linux")]
fn a_full_disk_while_writing_a_checkpoint_keeps_the_previous_one() {
    let dir = tempfile::tempdir().unwrap();
    let (out, ck) = (dir.path().join("out.exr"), dir.path().join("ck.rtkfilm"));
    let scene = root().join("scenes/cornell.toml");
    let base = |spp: &str| {
        vec![
            "render".to_string(),
            scene.to_str().unwrap().to_string(),
            "-q".into(),
            "-o".into(),
            out.to_str().unwrap().to_string(),
            "--set".into(),
            "render.width=64".into(),
            "--set".into(),
            "render.height=64".into(),
            "--spp".into(),
            spp.into(),
            "--checkpoint".into(),
            ck.to_str().unwrap().to_string(),
        ]
    };
    // A first checkpoint, of the first pass only: the one to keep.
    let mut first: Vec<String> = base("16");
    first.extend(["--time-limit".into(), "0".into()]);
    let r = Run::from(
        rtk(&first.iter().map(String::as_str).collect::<Vec<_>>())
            .output()
            .unwrap(),
    );
    assert!(r.ok, "{}", r.stderr);
    let kept = std::fs::read(&ck).unwrap();
    // Resuming it under a limit too small for a checkpoint (64x64 f64 sums
    // are 96 KiB): the first checkpoint write fails.
    let mut more = base("16");
    more.extend([
        "--resume".into(),
        ck.to_str().unwrap().to_string(),
        "--checkpoint-every".into(),
        "0".into(),
    ]);
    let r = render_under_fsize_limit(32, &more.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(!r.ok);
    assert!(r.stderr.contains("ck.rtkfilm"), "{}", r.stderr);
    assert_eq!(
        std::fs::read(&ck).unwrap(),
        kept,
        "the previous checkpoint changed"
    );
    // It still loads: resuming from it without the limit completes.
    let r = Run::from(
        rtk(&more.iter().map(String::as_str).collect::<Vec<_>>())
            .output()
            .unwrap(),
    );
    assert!(r.ok, "{}", r.stderr);
}
