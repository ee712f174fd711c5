//! `rtk conform PLUGIN_FILE`: the conformance suite rtk's own plugins pass,
//! run against any plugin library, built anywhere. One suite per kind:
//! objects and aggregates (object.rs), shaders (shader.rs), cameras,
//! lights and integrators (camera.rs, light.rs, integrator.rs); every kind
//! also gets `unknown-key-refused` and, given `--panic-param`,
//! `panics-reported` (panics.rs); objects, lights and integrators get
//! `stream-parity`, their ray-stream entries against the single-ray ones
//! (stream.rs). One line per check (pass, FAIL or skip); a
//! non-zero exit on any failure.
//!
//! The plugin is created with `--params` (default: none; when it refuses
//! none, the first TOML example of its README it accepts). A failure of
//! the plugin during a check (a refusal, a panic caught at the boundary)
//! fails that check with the plugin's message and ends the run there.

mod camera;
mod integrator;
mod interior;
mod light;
mod object;
mod panics;
mod shader;
mod stream;

use crate::stress::{header, Bench, Size};
use anyhow::{bail, Context, Result};
use rtk_kernel::RngState;
use std::path::{Path, PathBuf};

/// The arguments of `rtk conform`.
#[derive(clap::Args)]
#[command(after_long_help = CONFORM_HELP)]
pub struct ConformArgs {
    /// The plugin library (librtk_NAME.so, rtk_NAME.dll, librtk_NAME.dylib).
    pub plugin: PathBuf,
    /// Its class (default: from the file name).
    #[arg(long, value_name = "NAME")]
    pub class: Option<String>,
    /// Fewer scenes and rays (seconds).
    #[arg(long)]
    pub quick: bool,
    /// Print the results as JSON.
    #[arg(long)]
    pub json: bool,
    /// Threads the scenes are built for and the concurrency check runs on (at least 2).
    #[arg(long, default_value_t = 4, value_name = "N")]
    pub threads: usize,
    /// Extra folders to search for the other plugins (sphere, mesh, list,
    /// bvh...) after the plugin's own (repeatable).
    #[arg(long = "plugin-path", value_name = "DIR")]
    pub plugin_path: Vec<PathBuf>,
    /// Parameters for every instance of the plugin the suite creates: an
    /// inline TOML table (`'op = "union"'`, `'file = "bunny.ply", normals =
    /// "vertex"'`) or `@FILE`, a TOML file of them. Relative paths in keys
    /// named `file` or `*_file` are taken from the working directory (inline)
    /// or the file's folder (@FILE). Default: none; a plugin that refuses
    /// none is tried with its README's TOML examples, in order.
    #[arg(long, value_name = "TOML|@FILE")]
    pub params: Option<String>,
    /// Objects: the number of children each instance takes: `any` (an
    /// aggregate), 0 (a primitive) or N (exactly N, as `motion` takes 1 and
    /// `csg` 2). Default: found by trying 0 to 3 sphere children.
    #[arg(long, value_name = "N|any")]
    pub children: Option<String>,
    /// Objects: the class the plugin must answer exactly as, built over the
    /// same children (default: `list` for aggregates; none for plugins with a
    /// fixed number of children, whose answers are then checked for
    /// consistency only: the oracle checks are skipped).
    #[arg(long, value_name = "CLASS")]
    pub oracle: Option<String>,
    /// Parameters of the oracle (as --params).
    #[arg(long = "oracle-params", value_name = "TOML|@FILE", requires = "oracle")]
    pub oracle_params: Option<String>,
    /// A parameter of the plugin that makes it panic in the entry its value
    /// names (`panic_in` in rtk's test fixtures): runs `panics-reported`,
    /// which sets it to each entry of the plugin's kind in turn.
    #[arg(long = "panic-param", value_name = "KEY")]
    pub panic_param: Option<String>,
    /// Do not run this check; it is reported as `skip` (repeatable). E.g.
    /// `--skip furnace` for an integrator that does not estimate radiance.
    #[arg(long, value_name = "CHECK")]
    pub skip: Vec<String>,
    /// Run the checks in this process (the `rtk` binary runs them in a
    /// child process of itself, so that a plugin that aborts or crashes
    /// ends the child, not the suite's report).
    #[arg(long = "in-process", hide = true)]
    pub in_process: bool,
}

/// `rtk conform` as the binary runs it: the same command line in a child
/// process (with `--in-process`), its output passed through; a child ended
/// by a signal (a plugin that aborted or crashed: the child's handler has
/// named it) is reported as a failure of the suite, which still exits.
pub fn run_in_child() -> Result<()> {
    let exe = std::env::current_exe().context("finding the rtk binary to run the checks in")?;
    let mut args: Vec<std::ffi::OsString> = std::env::args_os().skip(1).collect();
    args.push("--in-process".into());
    let status = std::process::Command::new(&exe)
        .args(&args)
        .status()
        .with_context(|| format!("running {}", exe.display()))?;
    if status.success() {
        return Ok(());
    }
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        if let Some(sig) = status.signal() {
            println!("FAIL  (the suite)          the plugin ended the checks with signal {sig}; the checks after the last line above did not run");
            bail!("the conformance run was stopped by signal {sig} (see above)");
        }
    }
    std::process::exit(status.code().unwrap_or(1));
}

const CONFORM_HELP: &str = "\
Checks by kind (docs/plugins.md has the details):
  objects     children, nearest-hit, ties-lowest-index, any-hit, bounds-contain-hits,
              interval-respected, local-geom, nested-inside-bvh, bvh-nested-inside,
              concurrent-queries, stream-parity
  shaders     finite, energy, weight-matches-eval, pdf-matches-sample, pdf-integrates, reciprocity
  cameras     finite, unit-directions, time-in-shutter, pixel-centres, not-mirrored,
              deterministic, concurrent-queries
  lights      finite, delta-light, points-on-light (delta lights); at-infinity,
              li-matches-le, pdf-matches-sample, pdf-integrates (environment lights);
              pdf-matches-hit (area lights, on an emitting ball);
              deterministic, concurrent-queries, stream-parity
  integrators finite, furnace, black-without-light, deterministic, concurrent-queries,
              stream-parity
  every kind  unknown-key-refused, panics-reported (with --panic-param)

Examples:
  rtk conform librtk_bvh.so --quick
  rtk conform librtk_csg.so --params 'op = \"union\"' --oracle list
  rtk conform librtk_motion.so --params 'keyframes = [{ time = 0.0, translate = [0.5, 0.0, 0.0] }]' \\
      --oracle transform --oracle-params 'steps = [{ translate = [0.5, 0.0, 0.0] }]'
  rtk conform librtk_mesh.so --params 'file = \"scenes/meshes/bunny.ply\"'
  rtk conform librtk_normals.so --skip furnace --skip black-without-light
  rtk conform librtk_panicky.so --panic-param panic_in";

/// A check's outcome.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Status {
    Pass,
    Fail,
    /// Not applicable, or not asked for: said why.
    Skip,
}

/// One check's outcome.
pub(crate) struct Check {
    pub name: &'static str,
    pub status: Status,
    pub detail: String,
}

impl Check {
    /// Passed when `pass`, else failed.
    pub fn new(name: &'static str, pass: bool, detail: impl Into<String>) -> Check {
        Check {
            name,
            status: if pass { Status::Pass } else { Status::Fail },
            detail: detail.into(),
        }
    }
    /// Passed.
    pub fn pass(name: &'static str, detail: impl Into<String>) -> Check {
        Check::new(name, true, detail)
    }
    /// Not run, and why.
    pub fn skip(name: &'static str, why: impl Into<String>) -> Check {
        Check {
            name,
            status: Status::Skip,
            detail: why.into(),
        }
    }
    /// From a tally of failures (count, first): passes when there are none.
    pub fn tally(name: &'static str, slot: &(u64, String), of: u64, what: &str) -> Check {
        if slot.0 == 0 {
            Check::pass(name, format!("{of} {what} agree"))
        } else {
            Check::new(
                name,
                false,
                format!("{} of {of} {what} differ; first: {}", slot.0, slot.1),
            )
        }
    }
}

impl Check {
    /// From a tally of violations (count, first) of a property that must
    /// hold for each of `of` cases.
    pub fn held(name: &'static str, slot: &(u64, String), of: u64, what: &str) -> Check {
        if slot.0 == 0 {
            Check::pass(name, format!("held for {of} {what}"))
        } else {
            Check::new(
                name,
                false,
                format!("{} of {of} {what} fail; first: {}", slot.0, slot.1),
            )
        }
    }
}

/// Record a failure: its count, and the first one's description.
pub(crate) fn note(slot: &mut (u64, String), msg: impl FnOnce() -> String) {
    if slot.0 == 0 {
        slot.1 = msg();
    }
    slot.0 += 1;
}

/// The checks of a run so far, and the one under way: a plugin failure
/// while it runs fails it.
pub(crate) struct Suite {
    pub checks: Vec<Check>,
    phase: &'static str,
    /// Checks not to run, and why (`--skip`, or the README's `conform` block).
    skip: Vec<(String, String)>,
}

impl Suite {
    /// The check now running.
    pub fn at(&mut self, name: &'static str) {
        self.phase = name;
    }
    /// Add an outcome.
    pub fn push(&mut self, c: Check) {
        self.checks.push(c);
    }
    /// Whether `name` is to be run (not named by --skip); when not, its
    /// `skip` line is added.
    pub fn wants(&mut self, name: &'static str) -> bool {
        if let Some((_, why)) = self.skip.iter().find(|(s, _)| s == name) {
            self.checks.push(Check::skip(name, why.clone()));
            return false;
        }
        true
    }
}

/// A mistake in the arguments (not the plugin's failure): an error, not a
/// failed check.
#[derive(Debug)]
pub(crate) struct Usage(pub String);

impl std::fmt::Display for Usage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Usage {}

/// A plugin's kind, as the suites tell them apart.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Kind {
    Object,
    Shader,
    Camera,
    Light,
    Integrator,
}

/// Parameters for the plugin under test (or the oracle): a TOML table, its
/// values written into each definition the suite makes.
#[derive(Clone, Default)]
pub(crate) struct Params {
    pub table: toml::Table,
}

impl Params {
    /// `--params` text: an inline table's contents or `@FILE`.
    pub fn parse(arg: Option<&str>, flag: &str) -> Result<Params> {
        let Some(arg) = arg else {
            return Ok(Params::default());
        };
        // Errors name the file of `@FILE`.
        let label = match arg.strip_prefix('@') {
            Some(path) => format!("{flag} @{path}"),
            None => flag.to_string(),
        };
        let (text, base) = match arg.strip_prefix('@') {
            Some(path) => {
                let p = Path::new(path);
                // A regular file of at most a scene's size: a FIFO would
                // block and `/dev/zero` fill memory.
                let bytes = rtk_shell::file::read_regular_file(
                    p,
                    rtk_shell::file::MAX_SCENE_BYTES,
                    "parameter file",
                )
                .map_err(|e| anyhow::anyhow!("{label}: {e}"))?;
                let text = String::from_utf8(bytes)
                    .map_err(|_| anyhow::anyhow!("{label}: not UTF-8 text"))?;
                let dir = p.parent().map(Path::to_path_buf).unwrap_or_default();
                (text, dir)
            }
            None => (arg.to_string(), PathBuf::new()),
        };
        // An inline table's contents: one per line or comma-separated.
        let table: toml::Table = match toml::from_str(&text) {
            Ok(t) => t,
            Err(_) => toml::from_str::<toml::Table>(&format!("x = {{ {} }}", text.trim()))
                .ok()
                .and_then(|mut t| match t.remove("x") {
                    Some(toml::Value::Table(t)) => Some(t),
                    _ => None,
                })
                .with_context(|| {
                    let e = toml::from_str::<toml::Table>(&text)
                        .err()
                        .map(|e| e.to_string())
                        .unwrap_or_default();
                    format!("{label}: not a TOML table (`key = value, ...` or @FILE): {e}")
                })?,
        };
        for k in ["class", "children"] {
            if table.contains_key(k) {
                bail!("{flag}: `{k}` is not a parameter here (the class is the plugin's; children are the suite's, see --children)");
            }
        }
        let mut p = Params { table };
        p.resolve_files(&base)?;
        Ok(p)
    }

    /// Make relative paths of `file` and `*_file` keys absolute from `base`
    /// (the suite's scenes are read from a scratch folder), in nested
    /// tables too (a texture's `image_file`).
    pub fn resolve_files(&mut self, base: &Path) -> Result<()> {
        let root = std::env::current_dir()
            .context("the working directory")?
            .join(base);
        resolve_in(&mut self.table, &root);
        Ok(())
    }

    /// A copy with `key = value` added (or replaced).
    pub fn with(&self, key: &str, value: toml::Value) -> Params {
        let mut p = self.clone();
        p.table.insert(key.to_string(), value);
        p
    }

    /// `key = value` lines, for a `[section]`.
    pub fn lines(&self) -> String {
        self.table
            .iter()
            .map(|(k, v)| format!("{} = {v}\n", key(k)))
            .collect()
    }

    /// `key = value, ...`, for an inline table (empty when there are none).
    pub fn inline(&self) -> String {
        self.table
            .iter()
            .map(|(k, v)| format!("{} = {v}", key(k)))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// As JSON text, which `create` receives.
    pub fn json(&self) -> String {
        serde_json::to_string(&self.table).unwrap_or_else(|_| "{}".into())
    }

    /// For reports: the inline form, shortened.
    pub fn shown(&self) -> String {
        let s = self.inline();
        if s.is_empty() {
            "none".into()
        } else if s.chars().count() > 100 {
            format!("{}...", s.chars().take(97).collect::<String>())
        } else {
            s
        }
    }
}

/// A TOML key, quoted unless bare.
fn key(k: &str) -> String {
    if !k.is_empty()
        && k.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    {
        k.to_string()
    } else {
        toml::Value::String(k.to_string()).to_string()
    }
}

/// The definitions of class `class` in the ```toml examples of its README
/// (`doc`), as parameter tables (`class` and `children` left out), in order.
pub(crate) fn readme_examples(doc: &str, class: &str) -> Vec<Params> {
    let mut out = Vec::new();
    let mut block: Option<String> = None;
    for line in doc.lines() {
        let t = line.trim();
        match &mut block {
            None if t.starts_with("```toml") => block = Some(String::new()),
            Some(b) if t.starts_with("```") => {
                if let Ok(doc) = toml::from_str::<toml::Table>(b) {
                    collect_defs(&toml::Value::Table(doc), class, &mut out);
                }
                block = None;
            }
            Some(b) => {
                b.push_str(line);
                b.push('\n');
            }
            None => {}
        }
    }
    out
}

fn collect_defs(v: &toml::Value, class: &str, out: &mut Vec<Params>) {
    let toml::Value::Table(t) = v else { return };
    if t.get("class").and_then(|c| c.as_str()) == Some(class) {
        let mut table = t.clone();
        table.remove("class");
        table.remove("children");
        out.push(Params { table });
        return;
    }
    for v in t.values() {
        collect_defs(v, class, out);
    }
}

fn class_of(a: &ConformArgs) -> Result<String> {
    if let Some(c) = &a.class {
        return Ok(c.clone());
    }
    let stem = a
        .plugin
        .file_name()
        .and_then(|f| f.to_str())
        .context("the plugin's file name")?;
    let stem = stem
        .strip_prefix(std::env::consts::DLL_PREFIX)
        .unwrap_or(stem)
        .strip_suffix(std::env::consts::DLL_SUFFIX)
        .unwrap_or(stem);
    match stem.strip_prefix("rtk_") {
        Some(c) if rtk_shell::plugins::is_identifier(c) => Ok(c.to_string()),
        _ => bail!(
            "{}: cannot tell the class from the file name; say --class NAME",
            a.plugin.display()
        ),
    }
}

/// A TOML string.
pub(crate) fn toml_str(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

/// What every suite works with.
pub(crate) struct Cx<'a> {
    pub args: &'a ConformArgs,
    pub class: String,
    pub kind: Kind,
    /// The parameters in use (--params, or a README example).
    pub params: Params,
    /// --oracle-params.
    pub oracle_params: Params,
    /// --children.
    pub children: Option<object::Shape>,
    pub bench: Bench<'a>,
    pub rng: RngState,
    /// Threads queries may come from (the pool's).
    pub threads: usize,
    pub quick: bool,
    /// The plugin's README.
    pub doc: String,
}

impl Cx<'_> {
    /// `quick` or `full`, by the run's size.
    pub fn n(&self, quick: usize, full: usize) -> usize {
        if self.quick {
            quick
        } else {
            full
        }
    }
}

/// A scene that uses the plugin once, created with `params`: an object
/// with `children` sphere children under a `list` root; a shader bound to a
/// sphere; a light or a camera beside one; the integrator of a scene with a
/// Lambert sphere and a point light.
pub(crate) fn scene_using(kind: Kind, class: &str, params: &Params, children: usize) -> String {
    let ball = "[objects.ball]\nclass = \"sphere\"\n";
    let world = |kid: &str| format!("[objects.world]\nclass = \"list\"\nchildren = [{kid}]\n");
    let def = |section: &str| {
        format!(
            "[{section}]\nclass = {}\n{}",
            toml_str(class),
            params.lines()
        )
    };
    match kind {
        Kind::Object => {
            let mut s = header("world");
            let mut kids = Vec::new();
            for i in 0..children {
                s += &format!(
                    "[objects.c{i}]\nclass = \"sphere\"\ncenter = [{:?}, 0.0, 0.0]\nradius = 0.4\n",
                    i as f64 - 1.0
                );
                kids.push(format!("\"c{i}\""));
            }
            s += &def("objects.x");
            if children > 0 {
                s += &format!("children = [{}]\n", kids.join(", "));
            }
            s + &world("\"x\"")
        }
        Kind::Shader => {
            header("world")
                + &def("shaders.s")
                + ball
                + &world("{ object = \"ball\", shader = \"s\" }")
        }
        Kind::Light => header("world") + &def("lights.l") + ball + &world("\"ball\""),
        Kind::Camera => {
            "[render]\nroot = \"world\"\nintegrator = \"normals\"\nwidth = 16\nheight = 12\n"
                .to_string()
                + &def("cameras.c")
                + ball
                + &world("\"ball\"")
        }
        Kind::Integrator => {
            let inline = params.inline();
            format!(
                "[render]\nroot = \"world\"\nwidth = 8\nheight = 8\nintegrator = {{ class = {}{}{inline} }}\n\
                 [cameras.c]\nclass = \"pinhole\"\n[lights.l]\nclass = \"point\"\nposition = [0.0, 4.0, 4.0]\nintensity = [10.0, 10.0, 10.0]\n\
                 [shaders.white]\nclass = \"lambert\"\n",
                toml_str(class),
                if inline.is_empty() { "" } else { ", " }
            ) + ball
                + &world("{ object = \"ball\", shader = \"white\" }")
        }
    }
}

/// `unknown-key-refused`: the plugin refuses an unknown parameter, naming it.
pub(crate) fn unknown_key(cx: &mut Cx, children: usize) -> Check {
    let key = "conform_unknown_key";
    let scene = scene_using(
        cx.kind,
        &cx.class,
        &cx.params.with(key, toml::Value::Integer(1)),
        children,
    );
    let err = cx.bench.build_error(&scene);
    let pass = err.as_deref().is_some_and(|e| e.contains(key));
    Check::new(
        "unknown-key-refused",
        pass,
        match err {
            None => format!("`{key} = 1` was accepted"),
            Some(e) if e.contains(key) => "refused, naming the key".into(),
            Some(e) => format!("refused without naming the key: {}", e.replace('\n', " ")),
        },
    )
}

/// The first line of an error, from the plugin's name on (not the
/// scratch scene's file and line), shortened, for a report.
pub(crate) fn brief(e: &str) -> String {
    let l = e.lines().next().unwrap_or("");
    let l = match (l.contains("case.toml:"), l.find("plugin `")) {
        (true, Some(i)) => &l[i..],
        _ => l,
    };
    if l.chars().count() > 160 {
        format!("{}...", l.chars().take(157).collect::<String>())
    } else {
        l.to_string()
    }
}

/// Run `rtk conform`.
pub fn run(a: ConformArgs, pool: &rayon::ThreadPool) -> Result<()> {
    let plugin = load_plugin(&a)?;
    let class = plugin.class.clone();
    let kind = plugin.kind;
    // A plugin folder holding just this library, searched first.
    let folder = tempfile::Builder::new().prefix("rtk-conform").tempdir()?;
    let lib = folder
        .path()
        .join(rtk_shell::plugins::library_file_name(&class));
    std::fs::copy(&a.plugin, &lib)
        .with_context(|| format!("copying {} to {}", a.plugin.display(), lib.display()))?;
    let size = if a.quick { Size::Quick } else { Size::Full };
    let mut extra = vec![folder.path().to_path_buf()];
    extra.extend(a.plugin_path.iter().cloned());
    let bench = Bench::new(size, &extra, pool)?;
    check_object_flags(&a, kind, &class, &extra)?;
    let readme = ReadmeConform::parse(&plugin.doc, &class, folder.path())?;
    let params = match (&a.params, &readme.params) {
        (None, Some(p)) => p.clone(),
        _ => Params::parse(a.params.as_deref(), "--params")?,
    };
    let mut cx = Cx {
        args: &a,
        class: class.clone(),
        kind,
        params,
        oracle_params: Params::parse(a.oracle_params.as_deref(), "--oracle-params")?,
        children: a
            .children
            .as_deref()
            .map(object::parse_children)
            .transpose()?,
        bench,
        rng: RngState::seeded(0xC0F0),
        // Queries may come from as many threads as the scenes were built for.
        threads: pool.current_num_threads().max(1),
        quick: a.quick,
        doc: plugin.doc,
    };
    let mut skip: Vec<(String, String)> = a
        .skip
        .iter()
        .map(|s| (s.clone(), "--skip".into()))
        .collect();
    skip.extend(readme.skip.iter().cloned());
    let mut suite = Suite {
        checks: Vec::new(),
        phase: "create",
        skip: skip.clone(),
    };
    if let (None, Some(p)) = (&a.params, &readme.params) {
        suite.push(Check::pass(
            "params",
            format!("none given; the README's conform block: {}", p.shown()),
        ));
    }
    let label = run_suite(kind, plugin.shader_module, &mut cx, &mut suite)?;
    apply_skips(&skip, label, &mut suite)?;
    report(&a, &class, label, &cx.params, suite.checks)
}

/// The plugin under test as loaded: its class, kind, README and (for a
/// shader) its module.
struct Loaded {
    class: String,
    kind: Kind,
    doc: String,
    shader_module: Option<rtk_kernel::abi::ShaderModuleRef>,
}

/// Load `a.plugin`, saying what is wrong with the path before guessing a
/// class from its name; refuse kinds without a suite.
fn load_plugin(a: &ConformArgs) -> Result<Loaded> {
    match std::fs::metadata(&a.plugin) {
        Err(e) => bail!("{}: {e}", a.plugin.display()),
        Ok(m) if !m.is_file() => bail!("{}: not a regular file", a.plugin.display()),
        Ok(_) => {}
    }
    let class = class_of(a)?;
    let plugin = rtk_shell::plugins::load(&a.plugin, Some(&class))
        .map_err(|e| anyhow::anyhow!("{}: {e}", a.plugin.display()))?;
    let kind = match plugin.kind.name() {
        "object" => Kind::Object,
        "shader" => Kind::Shader,
        "camera" => Kind::Camera,
        "light" => Kind::Light,
        "integrator" => Kind::Integrator,
        other => bail!(
            "{}: `{class}` is a {other} plugin, which rtk conform has no suite for",
            a.plugin.display()
        ),
    };
    let doc = plugin.doc.clone();
    let shader_module = match plugin.module {
        rtk_shell::plugins::Module::Shader(m) => Some(m),
        _ => None,
    };
    Ok(Loaded {
        class,
        kind,
        doc,
        shader_module,
    })
}

/// `--children` and `--oracle` are for object plugins, and the oracle must
/// be a class on the plugin path (`extra` first): a misspelt one is a usage
/// error, said before any check runs (not a failed check of the plugin).
fn check_object_flags(a: &ConformArgs, kind: Kind, class: &str, extra: &[PathBuf]) -> Result<()> {
    if a.children.is_some() && kind != Kind::Object {
        bail!("--children is for object plugins; `{class}` is a {kind:?} plugin");
    }
    if a.oracle.is_some() && kind != Kind::Object {
        bail!("--oracle is for object plugins; `{class}` is a {kind:?} plugin");
    }
    if let Some(o) = &a.oracle {
        let file = rtk_shell::plugins::library_file_name(o);
        if !rtk_shell::plugins::is_identifier(o) {
            bail!("--oracle: `{o}` is not a class name (letters, digits, _)");
        }
        if rtk_shell::plugins::PluginPath::standard(extra)
            .find(o)
            .is_none()
        {
            bail!("--oracle: unknown class `{o}`: no {file} on the plugin path");
        }
    }
    Ok(())
}

/// Run the kind's suite into `suite`; returns the suite's name (an object
/// plugin that is an aggregate gets the aggregate suite). A plugin failure
/// ends the run with a failed check of the phase it happened in; a usage
/// error is returned.
fn run_suite(
    kind: Kind,
    shader_module: Option<rtk_kernel::abi::ShaderModuleRef>,
    cx: &mut Cx,
    suite: &mut Suite,
) -> Result<&'static str> {
    let mut label = match kind {
        Kind::Object => "object",
        Kind::Shader => "shader",
        Kind::Camera => "camera",
        Kind::Light => "light",
        Kind::Integrator => "integrator",
    };
    let res = match kind {
        Kind::Object => object::checks(cx, suite).map(|shape| {
            if shape.is_aggregate() {
                label = "aggregate";
            }
        }),
        Kind::Shader => shader_module
            .context("the shader's module")
            .and_then(|m| shader::checks(m, cx, suite)),
        Kind::Camera => camera::checks(cx, suite),
        Kind::Light => light::checks(cx, suite),
        Kind::Integrator => integrator::checks(cx, suite),
    };
    if let Err(e) = res {
        if e.downcast_ref::<Usage>().is_some() {
            return Err(e);
        }
        let phase = suite.phase;
        suite.push(Check::new(
            phase,
            false,
            format!("stopped: {}", brief(&format!("{e:#}"))),
        ));
    }
    Ok(label)
}

/// Every --skip must name a check of this suite (a misspelt one would
/// silently run it); the checks it names are reported as skipped.
fn apply_skips(skip: &[(String, String)], label: &str, suite: &mut Suite) -> Result<()> {
    for (s, why) in skip {
        if !suite.checks.iter().any(|c| c.name == s) {
            let names: Vec<&str> = suite.checks.iter().map(|c| c.name).collect();
            let by = if why == "--skip" {
                "--skip"
            } else {
                "the README's conform block: skip"
            };
            bail!(
                "{by} {s}: the {label} suite has no check of that name (its checks: {})",
                names.join(", ")
            );
        }
    }
    for c in suite.checks.iter_mut() {
        if let Some((_, why)) = skip.iter().find(|(s, _)| s == c.name) {
            if c.status != Status::Skip {
                *c = Check::skip(c.name, why.clone());
            }
        }
    }
    Ok(())
}

/// [`Params::resolve_files`] in one table.
fn resolve_in(table: &mut toml::Table, root: &Path) {
    for (k, v) in table.iter_mut() {
        match v {
            toml::Value::String(s)
                if (k == "file" || k.ends_with("_file")) && Path::new(s.as_str()).is_relative() =>
            {
                *s = root.join(s.as_str()).display().to_string();
            }
            toml::Value::Table(t) => resolve_in(t, root),
            _ => {}
        }
    }
}

/// What a plugin's README tells the suite, in a fenced block whose info
/// string is `conform` (TOML): `params`, the parameters to use when none
/// are given (relative `file` paths resolve against the block's `files`);
/// `files`, a table of file names and contents the suite writes for them
/// (a tiny mesh for a class that needs one); `skip`, checks that do not
/// apply to the class, each with the reason the report prints. So a
/// plugin passes its suite with no arguments, saying why where a check
/// does not fit it (`normals` estimates no radiance), and a third-party
/// plugin can do the same in its own README.
#[derive(Default)]
struct ReadmeConform {
    params: Option<Params>,
    skip: Vec<(String, String)>,
}

impl ReadmeConform {
    /// The first `conform` block of `doc`, its files written into `dir`.
    fn parse(doc: &str, class: &str, dir: &Path) -> Result<ReadmeConform> {
        let Some(text) = fenced_block(doc, "conform") else {
            return Ok(ReadmeConform::default());
        };
        let bad = |m: String| anyhow::anyhow!("`{class}`'s README, its conform block: {m}");
        let mut t: toml::Table = toml::from_str(&text).map_err(|e| bad(e.to_string()))?;
        if let Some(files) = t.remove("files") {
            let toml::Value::Table(files) = files else {
                return Err(bad(
                    "`files` must be a table of file names and contents".into()
                ));
            };
            for (name, body) in files {
                let ok_name = Path::new(&name).file_name().and_then(|f| f.to_str()) == Some(&name);
                match body {
                    toml::Value::String(b) if ok_name => std::fs::write(dir.join(&name), b)
                        .with_context(|| format!("writing {}", dir.join(&name).display()))?,
                    _ => return Err(bad(format!("files.{name}: a plain file name and its text"))),
                }
            }
        }
        let params = match t.remove("params") {
            None => None,
            Some(toml::Value::Table(table)) => {
                let mut p = Params { table };
                p.resolve_files(dir)?;
                Some(p)
            }
            Some(_) => return Err(bad("`params` must be a table".into())),
        };
        let skip = match t.remove("skip") {
            None => Vec::new(),
            Some(toml::Value::Table(s)) => s
                .into_iter()
                .map(|(k, v)| match v {
                    toml::Value::String(why) => Ok((k, format!("the plugin's README: {why}"))),
                    _ => Err(bad(format!("skip.{k}: give the reason as a string"))),
                })
                .collect::<Result<_>>()?,
            Some(_) => {
                return Err(bad(
                    "`skip` must be a table of check names and reasons".into()
                ))
            }
        };
        if let Some(k) = t.keys().next() {
            return Err(bad(format!("unknown key `{k}` (params, files, skip)")));
        }
        Ok(ReadmeConform { params, skip })
    }
}

/// The text of the first fenced block of `doc` whose info string is `info`.
fn fenced_block(doc: &str, info: &str) -> Option<String> {
    let mut block: Option<String> = None;
    for line in doc.lines() {
        let t = line.trim();
        match &mut block {
            None if t.strip_prefix("```").map(str::trim) == Some(info) => {
                block = Some(String::new())
            }
            Some(b) if t.starts_with("```") => return Some(std::mem::take(b)),
            Some(b) => {
                b.push_str(line);
                b.push('\n');
            }
            None => {}
        }
    }
    None
}

/// Print the checks (lines or JSON); an error when any failed.
fn report(
    a: &ConformArgs,
    class: &str,
    kind: &str,
    params: &Params,
    checks: Vec<Check>,
) -> Result<()> {
    let failed = checks.iter().filter(|c| c.status == Status::Fail).count();
    let skipped = checks.iter().filter(|c| c.status == Status::Skip).count();
    if a.json {
        let list: Vec<_> = checks
            .iter()
            .map(|c| {
                serde_json::json!({"check": c.name, "pass": c.status != Status::Fail,
                    "status": match c.status { Status::Pass => "pass", Status::Fail => "fail", Status::Skip => "skip" },
                    "detail": c.detail})
            })
            .collect();
        println!(
            "{}",
            serde_json::json!({"plugin": a.plugin.display().to_string(), "class": class,
                "kind": kind, "aggregate": kind == "aggregate", "params": params.inline(),
                "checks": list, "failed": failed, "skipped": skipped})
        );
    } else {
        for c in &checks {
            match c.status {
                Status::Pass => println!("pass  {:<22} {}", c.name, c.detail),
                Status::Fail => println!("FAIL  {:<22} {}", c.name, c.detail),
                Status::Skip => println!("skip  {:<22} ({})", c.name, c.detail),
            }
        }
        println!(
            "{class} ({}): {} checks, {failed} failed{}",
            a.plugin.display(),
            checks.len(),
            if skipped > 0 {
                format!(", {skipped} skipped")
            } else {
                String::new()
            }
        );
    }
    if failed > 0 {
        bail!("`{class}` fails {failed} conformance check(s)");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn params_parse_inline_and_write_back() {
        let p = Params::parse(
            Some(r#"op = "union", keyframes = [{ time = 0.0, rotate = { axis = [0.0, 1.0, 0.0], angle = 30.0 } }]"#),
            "--params",
        )
        .unwrap();
        assert_eq!(p.table["op"].as_str(), Some("union"));
        let back: toml::Table = toml::from_str(&p.lines()).unwrap();
        assert_eq!(back, p.table);
        let inline: toml::Table = toml::from_str(&format!("x = {{ {} }}", p.inline())).unwrap();
        assert_eq!(inline["x"].as_table().unwrap(), &p.table);
        let lines = Params::parse(Some("op = \"union\"\nn = 2"), "--params").unwrap();
        assert_eq!(lines.table.len(), 2);
        assert!(Params::parse(Some("class = \"x\""), "--params").is_err());
        assert!(Params::parse(Some("op = "), "--params").is_err());
    }

    #[test]
    fn file_keys_become_absolute() {
        let p = Params::parse(Some(r#"file = "m/x.ply", other = "y""#), "--params").unwrap();
        assert!(Path::new(p.table["file"].as_str().unwrap()).is_absolute());
        assert_eq!(p.table["other"].as_str(), Some("y"));
    }

    #[test]
    fn readme_examples_are_found() {
        let doc = "text\n```toml\n[objects.a]\nclass = \"bicubic\"\nfile = \"t.bpt\"\n\n[objects.w]\nclass = \"list\"\nchildren = [\"a\"]\n```\n\
                   ```toml\n[objects.b]\nclass = \"bicubic\"\npatches = [[[0.0, 0.0, 0.0]]]\n```\n";
        let ex = readme_examples(doc, "bicubic");
        assert_eq!(ex.len(), 2);
        assert!(ex[0].table.contains_key("file"));
        assert!(ex[1].table.contains_key("patches"));
        let int = "```toml\n[render]\nintegrator = { class = \"path\", rr_depth = 5 }\n```\n";
        assert_eq!(
            readme_examples(int, "path")[0].table["rr_depth"].as_integer(),
            Some(5)
        );
    }
}
