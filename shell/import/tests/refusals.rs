//! What the importer refuses: each construct rtk cannot express exactly
//! is an [`ImportError::Unsupported`] whose message names the file, line
//! and column of the element, the plugin (`<bsdf type="plastic">`) and the
//! parameter; with `lenient` the same scene imports, with exactly one
//! warning line for the dropped thing, and that line says what the error
//! said.

use rtk_import::{import, ImportError, Options};
use std::path::Path;

/// A scene around `body`: an integrator, a sensor (its extra properties),
/// a film's filter, and a sphere that always translates.
fn scene(integrator: &str, sensor: &str, filter: &str, body: &str) -> String {
    format!(
        r#"<?xml version="1.0"?>
<scene version="3.0.0">
    {integrator}
    <sensor type="perspective">
        <float name="fov" value="45"/>
        {sensor}
        <film type="hdrfilm">
            <integer name="width" value="8"/>
            <integer name="height" value="8"/>
            {filter}
        </film>
    </sensor>
    <shape type="sphere"/>
    {body}
</scene>
"#
    )
}

const BOX: &str = r#"<rfilter type="box"/>"#;

/// One refusal: the scene, the text the element starts with (its
/// location is where it is), and what the message must name.
struct Case {
    name: &'static str,
    xml: String,
    at: &'static str,
    names: &'static [&'static str],
}

fn cases() -> Vec<Case> {
    let body = |b: &str| scene("", "", BOX, b);
    let integrator = |i: &str| scene(i, "", BOX, "");
    vec![
        Case {
            name: "an unknown BSDF plugin",
            xml: body(r#"<shape type="sphere"><bsdf type="principled"/></shape>"#),
            at: r#"<bsdf type="principled""#,
            names: &[r#"<bsdf type="principled">"#],
        },
        Case {
            name: "an anisotropic rough plastic",
            xml: body(
                r#"<shape type="sphere"><bsdf type="roughplastic"><float name="alpha_u" value="0.2"/></bsdf></shape>"#,
            ),
            at: r#"<float name="alpha_u""#,
            names: &[r#"<bsdf type="roughplastic">"#, "`alpha_u`"],
        },
        Case {
            name: "an unknown shape plugin",
            xml: body(r#"<shape type="cube"/>"#),
            at: r#"<shape type="cube""#,
            names: &[r#"<shape type="cube">"#],
        },
        Case {
            name: "an unknown parameter",
            xml: body(r#"<shape type="sphere"><float name="wobble" value="1"/></shape>"#),
            at: r#"<float name="wobble""#,
            names: &[r#"<shape type="sphere">"#, "`wobble`"],
        },
        Case {
            name: "a gaussian rfilter of another width",
            xml: scene(
                "",
                "",
                r#"<rfilter type="gaussian"><float name="stddev" value="1"/></rfilter>"#,
                "",
            ),
            at: r#"<float name="stddev""#,
            names: &[r#"<rfilter type="gaussian">"#, "`stddev`"],
        },
        Case {
            name: "hidden emitters",
            xml: integrator(
                r#"<integrator type="path"><boolean name="hide_emitters" value="true"/></integrator>"#,
            ),
            at: r#"<boolean name="hide_emitters""#,
            names: &[r#"<integrator type="path">"#, "`hide_emitters`"],
        },
        Case {
            name: "two emitter samples",
            xml: integrator(
                r#"<integrator type="direct"><integer name="emitter_samples" value="2"/></integrator>"#,
            ),
            at: r#"<integer name="emitter_samples""#,
            names: &[r#"<integrator type="direct">"#, "`emitter_samples`"],
        },
        Case {
            name: "a mirrored camera",
            xml: scene(
                "",
                r#"<transform name="to_world"><scale x="-1"/></transform>"#,
                BOX,
                "",
            ),
            at: r#"<transform name="to_world""#,
            names: &[r#"<sensor type="perspective">"#, "`to_world`", "mirror"],
        },
        Case {
            name: "volpath",
            xml: integrator(r#"<integrator type="volpath"/>"#),
            at: r#"<integrator type="volpath""#,
            names: &[r#"<integrator type="volpath">"#, "media"],
        },
        Case {
            name: "flipped normals",
            xml: body(
                r#"<shape type="sphere"><boolean name="flip_normals" value="true"/></shape>"#,
            ),
            at: r#"<boolean name="flip_normals""#,
            names: &[r#"<shape type="sphere">"#, "`flip_normals`"],
        },
        Case {
            name: "a checkerboard texture",
            xml: body(
                r#"<shape type="sphere"><bsdf type="diffuse"><texture name="reflectance" type="checkerboard"/></bsdf></shape>"#,
            ),
            at: r#"<texture name="reflectance""#,
            names: &[r#"<texture type="checkerboard">"#],
        },
        Case {
            name: "an unjittered stratified sampler",
            xml: scene(
                "",
                r#"<sampler type="stratified"><boolean name="jitter" value="false"/></sampler>"#,
                BOX,
                "",
            ),
            at: r#"<boolean name="jitter""#,
            names: &[r#"<sampler type="stratified">"#, "`jitter`"],
        },
        Case {
            name: "an emitting rectangle",
            xml: body(r#"<shape type="rectangle"><emitter type="area"/></shape>"#),
            at: r#"<emitter type="area""#,
            names: &[r#"<emitter type="area">"#, "polygon"],
        },
        Case {
            name: "a medium",
            xml: body(r#"<medium type="homogeneous" id="fog"/>"#),
            at: r#"<medium type="homogeneous""#,
            names: &[r#"<medium type="homogeneous">"#],
        },
    ]
}

/// Line and column (from 1) of the first `needle` in `text`.
fn line_col(text: &str, needle: &str) -> (usize, usize) {
    let at = text.find(needle).expect("the needle is in the scene");
    let before = &text[..at];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().unwrap().chars().count() + 1;
    (line, col)
}

fn import_text(dir: &Path, xml: &str, lenient: bool) -> Result<rtk_import::Imported, ImportError> {
    let path = dir.join("scene.xml");
    std::fs::write(&path, xml).unwrap();
    import(
        &path,
        &Options {
            lenient,
            out_dir: dir.to_path_buf(),
            ..Default::default()
        },
    )
}

#[test]
fn each_unsupported_construct_is_refused_at_its_element_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.xml");
    for c in cases() {
        let e = match import_text(dir.path(), &c.xml, false) {
            Err(e @ ImportError::Unsupported { .. }) => e,
            other => panic!("{}: expected Unsupported, got {other:?}", c.name),
        };
        let msg = e.to_string();
        let (line, col) = line_col(&c.xml, c.at);
        let loc = format!("{}:{line}:{col}: ", path.display());
        assert!(msg.starts_with(&loc), "{}: `{msg}` is not at {loc}", c.name);
        for n in c.names {
            assert!(msg.contains(n), "{}: `{msg}` does not name {n}", c.name);
        }
    }
}

#[test]
fn lenient_drops_each_with_exactly_one_warning_line() {
    let dir = tempfile::tempdir().unwrap();
    for c in cases() {
        let strict = import_text(dir.path(), &c.xml, false).unwrap_err();
        let done = import_text(dir.path(), &c.xml, true)
            .unwrap_or_else(|e| panic!("{}: lenient still refuses: {e}", c.name));
        assert_eq!(
            done.warnings,
            vec![format!("warning: {strict} (dropped: --lenient)")],
            "{}",
            c.name
        );
        assert!(!done.warnings[0].contains('\n'), "{}", c.name);
        let toml: toml::Table = toml::from_str(&done.toml)
            .unwrap_or_else(|e| panic!("{}: the TOML does not parse: {e}", c.name));
        assert!(toml.contains_key("render"), "{}", c.name);
    }
}

#[test]
fn lenient_warns_once_per_dropped_thing() {
    let dir = tempfile::tempdir().unwrap();
    let xml = scene(
        r#"<integrator type="path"><boolean name="hide_emitters" value="true"/></integrator>"#,
        "",
        BOX,
        r#"<shape type="sphere"><float name="a" value="1"/><float name="b" value="2"/></shape>
    <bsdf type="principled" id="shared"/>
    <shape type="sphere"><ref id="shared"/></shape>
    <shape type="sphere"><ref id="shared"/></shape>"#,
    );
    let done = import_text(dir.path(), &xml, true).unwrap();
    // hide_emitters, a, b, and the shared principled once; the four spheres
    // all stay, the principled one's two with Mitsuba's default diffuse.
    assert_eq!(done.warnings.len(), 4, "{:#?}", done.warnings);
    assert_eq!(done.toml.matches("mitsuba_default_diffuse\" }").count(), 4);
}
