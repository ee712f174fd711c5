//! Hostile and broken Mitsuba scenes (the importer's part of the hostile
//! catalogue, `hostile.rs`): each case runs `rtk import X.xml -o out.toml`
//! and `rtk render X.xml -o out.png` in a folder of its own, and both must
//! exit non-zero within [`DEADLINE`], say in stderr which file and (where
//! there is one) which line and column, with a clear message, and write
//! nothing (the folder holds exactly the case's own files afterwards).
//!
//! A texture whose header declares 100,000 x 100,000 pixels is refused at
//! import, at its `filename`, from the header alone. A 100 MB attribute is
//! not needed: a scene file is refused above 64 MiB by its size, before it
//! is read.

use rtk_tests::*;
use std::path::Path;
use std::time::{Duration, Instant};

/// The longest a case may take: every refusal comes before rendering.
const DEADLINE: Duration = Duration::from_secs(30);

/// A scene that imports and renders, around `body`.
fn scene(body: &str) -> String {
    format!(
        r#"<?xml version="1.0"?>
<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="45"/>
        <film type="hdrfilm">
            <integer name="width" value="8"/>
            <integer name="height" value="8"/>
            <rfilter type="box"/>
        </film>
    </sensor>
    <shape type="sphere"/>
{body}
</scene>
"#
    )
}

/// One hostile input: its files (the first is the scene), and what
/// stderr must say.
struct Case {
    name: &'static str,
    files: Vec<(String, Vec<u8>)>,
    expect: Vec<String>,
}

fn case(name: &'static str, text: impl Into<Vec<u8>>, expect: &[&str]) -> Case {
    Case {
        name,
        files: vec![("X.xml".into(), text.into())],
        expect: expect.iter().map(|s| s.to_string()).collect(),
    }
}

impl Case {
    fn with(mut self, name: &str, text: impl Into<Vec<u8>>) -> Self {
        self.files.push((name.into(), text.into()));
        self
    }
}

/// An 8-bit RGB PNG of `w` x `h` pixels with an empty image-data chunk:
/// a well-formed header that promises a huge image.
fn png_header(w: u32, h: u32) -> Vec<u8> {
    let mut ihdr = w.to_be_bytes().to_vec();
    ihdr.extend(h.to_be_bytes());
    ihdr.extend([8, 2, 0, 0, 0]);
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    for (kind, data) in [(b"IHDR", ihdr), (b"IDAT", vec![]), (b"IEND", vec![])] {
        let mut chunk = kind.to_vec();
        chunk.extend(&data);
        // CRC-32 (ISO 3309) of the chunk type and data, as PNG requires.
        let mut crc = !0u32;
        for &b in &chunk {
            crc ^= b as u32;
            for _ in 0..8 {
                crc = if crc & 1 != 0 {
                    (crc >> 1) ^ 0xEDB8_8320
                } else {
                    crc >> 1
                };
            }
        }
        png.extend((data.len() as u32).to_be_bytes());
        png.extend(&chunk);
        png.extend((!crc).to_be_bytes());
    }
    png
}

/// `depth` files `inc0.xml` ... each including the next, the last a shape.
fn include_chain(depth: usize) -> Case {
    let mut c = case(
        "includes nested deeper than 16",
        scene(r#"    <include filename="inc0.xml"/>"#),
        &["inc14.xml:2:5: ", "includes nested more than 16 deep"],
    );
    for k in 0..depth {
        let inner = if k + 1 == depth {
            r#"<shape type="sphere"/>"#.to_string()
        } else {
            format!(r#"<include filename="inc{}.xml"/>"#, k + 1)
        };
        c = c.with(
            &format!("inc{k}.xml"),
            format!("<scene version=\"3.0.0\">\n    {inner}\n</scene>\n"),
        );
    }
    c
}

/// A billion laughs: entities of entities, ten to the ninth `lol`s.
fn entity_bomb() -> String {
    let mut s =
        String::from("<?xml version=\"1.0\"?>\n<!DOCTYPE scene [\n <!ENTITY lol \"lol\">\n");
    for k in 1..10 {
        let prev = if k == 1 {
            "lol".to_string()
        } else {
            format!("lol{}", k - 1)
        };
        let body: String = (0..10).map(|_| format!("&{prev};")).collect();
        s += &format!(" <!ENTITY lol{k} \"{body}\">\n");
    }
    s + "]>\n<scene version=\"3.0.0\"><string name=\"x\" value=\"&lol9;\"/></scene>\n"
}

/// `<shape>`s nested `depth` deep.
fn deep_nesting(depth: usize) -> String {
    let mut s = String::from("<scene version=\"3.0.0\">\n");
    s += &"<shape type=\"sphere\">".repeat(depth);
    s += &"</shape>".repeat(depth);
    s + "\n</scene>\n"
}

fn cases() -> Vec<Case> {
    vec![
        case(
            "malformed XML (an unclosed tag)",
            "<scene version=\"3.0.0\">\n    <shape type=\"sphere\">\n</scene>\n",
            &["X.xml:3:1: ", "malformed XML", "expected 'shape' tag"],
        ),
        case(
            "not UTF-8",
            b"<scene version=\"3.0.0\">\xff\xfe</scene>\n".to_vec(),
            &["X.xml: ", "not UTF-8"],
        ),
        case("an empty file", "", &["X.xml:1:1: ", "malformed XML"]),
        case(
            "a root that is not <scene>",
            "<?xml version=\"1.0\"?>\n<mitsuba version=\"3.0.0\"/>\n",
            &["X.xml:2:1: ", "the root element is <mitsuba>"],
        ),
        case(
            "no version",
            "<scene>\n    <shape type=\"sphere\"/>\n</scene>\n",
            &["X.xml:1:1: ", "needs a version attribute"],
        ),
        case(
            "a missing mesh file",
            scene("    <shape type=\"obj\">\n        <string name=\"filename\" value=\"missing.obj\"/>\n    </shape>"),
            &["X.xml:13:9: ", "`missing.obj` does not exist"],
        ),
        case(
            "a texture whose header declares 100,000 x 100,000 texels",
            scene("    <shape type=\"rectangle\">\n        <bsdf type=\"diffuse\">\n            <texture type=\"bitmap\" name=\"reflectance\">\n                <string name=\"filename\" value=\"huge.png\"/>\n            </texture>\n        </bsdf>\n    </shape>"),
            &["X.xml:15:17: ", "huge.png declares 100000 x 100000 texels"],
        )
        .with("huge.png", png_header(100_000, 100_000)),
        case(
            "a missing spectrum file",
            scene("    <shape type=\"sphere\">\n        <bsdf type=\"diffuse\">\n            <spectrum name=\"reflectance\" filename=\"gone.spd\"/>\n        </bsdf>\n    </shape>"),
            &["X.xml:14:13: ", "cannot read", "gone.spd"],
        ),
        case(
            "a spectrum file with three numbers on a line",
            scene("    <shape type=\"sphere\">\n        <bsdf type=\"diffuse\">\n            <spectrum name=\"reflectance\" filename=\"bad.spd\"/>\n        </bsdf>\n    </shape>"),
            &["X.xml:14:13: ", "bad.spd:2: expected two numbers"],
        )
        .with("bad.spd", "400 0.5\n500 0.6 0.7\n"),
        case(
            "a conductor material with no spectra beside the scene",
            scene("    <shape type=\"sphere\">\n        <bsdf type=\"conductor\">\n            <string name=\"material\" value=\"Unobtainium\"/>\n        </bsdf>\n    </shape>"),
            &["X.xml:13:9: ", "material `Unobtainium`", "ior/Unobtainium.eta.spd"],
        ),
        case(
            "an include cycle",
            scene("    <include filename=\"b.xml\"/>"),
            &["b.xml:2:5: ", "include cycle", "X.xml -> ", "b.xml -> "],
        )
        .with("b.xml", "<scene version=\"3.0.0\">\n    <include filename=\"X.xml\"/>\n</scene>\n"),
        include_chain(20),
        case(
            "an undefined $param",
            scene("    <shape type=\"sphere\">\n        <float name=\"radius\" value=\"$size\"/>\n    </shape>"),
            &["X.xml:13:9: ", "undefined parameter: $size"],
        ),
        case(
            "a <ref> to an unknown id",
            scene("    <shape type=\"sphere\">\n        <ref id=\"nowhere\"/>\n    </shape>"),
            &["X.xml:13:9: ", "<ref id=\"nowhere\">", "no object with this id"],
        ),
        case(
            "an unknown plugin type",
            scene("    <shape type=\"teapot\"/>"),
            &["X.xml:12:5: ", "<shape type=\"teapot\">", "rtk translates the shapes"],
        ),
        case(
            "a DTD (an entity bomb)",
            entity_bomb(),
            &["X.xml:2:1: ", "malformed XML", "<!DOCTYPE>", "expands no entities"],
        ),
        case(
            "elements nested 10,000 deep",
            deep_nesting(10_000),
            &["X.xml:2:", "elements nested more than 64 deep"],
        ),
    ]
}

/// The folder's file names, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// Run one command of a case; the problems found.
fn run(c: &Case, args: &[&str]) -> Vec<String> {
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in &c.files {
        std::fs::write(dir.path().join(name), bytes).unwrap();
    }
    let before = listing(dir.path());
    let start = Instant::now();
    let r = Run::from(rtk(args).current_dir(dir.path()).output().unwrap());
    let took = start.elapsed();
    let what = format!("{}: rtk {}", c.name, args.join(" "));
    let mut problems = vec![];
    if r.ok {
        problems.push(format!("{what}: succeeded"));
    }
    if took > DEADLINE {
        problems.push(format!("{what}: took {took:?}"));
    }
    for e in &c.expect {
        if !r.stderr.contains(e.as_str()) {
            problems.push(format!("{what}: stderr lacks {e:?}:\n{}", r.stderr));
        }
    }
    if r.stderr.lines().count() > 20 {
        problems.push(format!(
            "{what}: {} lines of stderr",
            r.stderr.lines().count()
        ));
    }
    let after = listing(dir.path());
    if after != before {
        problems.push(format!("{what}: left {after:?} (had {before:?})"));
    }
    problems
}

#[test]
fn hostile_mitsuba_scenes_are_refused_located_and_write_nothing() {
    // Built before the clock of the first case starts.
    let _ = rtk_path();
    let mut problems = vec![];
    for c in cases() {
        problems.extend(run(&c, &["import", "X.xml", "-o", "out.toml"]));
        problems.extend(run(&c, &["render", "X.xml", "-o", "out.png"]));
    }
    assert!(problems.is_empty(), "{}", problems.join("\n\n"));
}

#[test]
fn the_base_scene_imports_and_renders() {
    // The cases' failures are theirs, not the scene around them.
    let c = case("the base scene", scene(""), &[]);
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("X.xml"), &c.files[0].1).unwrap();
    for args in [
        &["import", "X.xml", "-o", "out.toml"][..],
        &["render", "X.xml", "-o", "out.png"][..],
    ] {
        let r = Run::from(rtk(args).current_dir(dir.path()).output().unwrap());
        assert!(r.ok, "rtk {}: {}", args.join(" "), r.stderr);
    }
    assert!(dir.path().join("out.toml").is_file());
    assert!(dir.path().join("out.png").is_file());
}
