//! A render farm (issue 11, docs/farm.md): crops rendered separately and
//! stitched by `rtk merge` equal a single render bit for bit; the local
//! `xargs -P 2` split of docs/farm.md runs as written. And `rtk plugins
//! --check` reports broken libraries.

use rtk_tests::*;

/// The `sh` block after `<!-- farm-local -->` in docs/farm.md.
fn local_block() -> String {
    let doc = std::fs::read_to_string(root().join("docs/farm.md")).expect("docs/farm.md");
    let after = doc
        .split_once("<!-- farm-local -->")
        .expect("the farm-local marker")
        .1;
    let body = after
        .split_once("```sh\n")
        .expect("a sh block")
        .1
        .split_once("```")
        .expect("its end")
        .0;
    body.to_string()
}

fn bits(i: &Image) -> Vec<u32> {
    i.data.iter().map(|v| v.to_bits()).collect()
}

#[test]
#[cfg(unix)]
fn local_split_with_xargs_matches_a_single_render() {
    let dir = tempfile::tempdir().unwrap();
    let scene = root().join("scenes/cornell.toml");
    // A size that does not divide into tiles or bands evenly.
    let (w, h, n) = ("37", "29", "5");
    let o = std::process::Command::new("sh")
        .arg("-c")
        .arg(local_block())
        .current_dir(dir.path())
        .env("RTK", rtk_path())
        .env("SCENE", &scene)
        .env("W", w)
        .env("H", h)
        .env("N", n)
        .env_remove("RTK_PLUGIN_PATH")
        .output()
        .expect("sh");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let merged = Image::read(&dir.path().join("out.exr"));
    for threads in ["1", "2"] {
        let full = dir.path().join(format!("full-{threads}.exr"));
        let run = Run::from(
            rtk(&[
                "render",
                scene.to_str().unwrap(),
                "--set",
                &format!("render.width={w}"),
                "--set",
                &format!("render.height={h}"),
                "--threads",
                threads,
                "-q",
                "-o",
                full.to_str().unwrap(),
            ])
            .output()
            .unwrap(),
        );
        assert!(run.ok, "{}", run.stderr);
        assert_eq!(
            bits(&merged),
            bits(&Image::read(&full)),
            "{threads} threads"
        );
    }
}

#[test]
fn a_crop_image_is_that_part_of_the_full_image_and_merge_refuses_gaps() {
    let dir = tempfile::tempdir().unwrap();
    let scene = root().join("scenes/cornell.toml");
    let s = scene.to_str().unwrap();
    let size = [
        "--set",
        "render.width=24",
        "--set",
        "render.height=20",
        "--spp",
        "4",
        "-q",
    ];
    let out = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let go = |extra: &[&str]| {
        let mut a = vec!["render", s];
        a.extend_from_slice(&size);
        a.extend_from_slice(extra);
        Run::from(rtk(&a).output().unwrap())
    };
    assert!(go(&["-o", &out("full.exr")]).ok);
    let run = go(&["--crop", "5,3,21,17", "-o", &out("crop.exr")]);
    assert!(run.ok, "{}", run.stderr);
    let (full, crop) = (
        Image::read(&dir.path().join("full.exr")),
        Image::read(&dir.path().join("crop.exr")),
    );
    assert_eq!((crop.width, crop.height), (16, 14));
    for y in 0..14 {
        for x in 0..16 {
            assert_eq!(crop.px(x, y), full.px(x + 5, y + 3), "pixel ({x}, {y})");
        }
    }
    // Two crops of three: merge names the gap.
    assert!(go(&["--crop", "0,0,24,10", "-o", &out("p0.rtkfilm")]).ok);
    assert!(go(&["--crop", "0,10,12,20", "-o", &out("p1.rtkfilm")]).ok);
    let run = Run::from(
        rtk(&[
            "merge",
            &out("m.exr"),
            &out("p0.rtkfilm"),
            &out("p1.rtkfilm"),
        ])
        .output()
        .unwrap(),
    );
    assert!(!run.ok);
    assert!(
        run.stderr
            .contains("leave 120 pixels of the 24x20 image uncovered, the first (12, 10)"),
        "{}",
        run.stderr
    );
    assert!(!dir.path().join("m.exr").exists());
    // Overlap.
    let run = Run::from(
        rtk(&[
            "merge",
            &out("m.exr"),
            &out("p0.rtkfilm"),
            &out("p0.rtkfilm"),
        ])
        .output()
        .unwrap(),
    );
    assert!(!run.ok);
    assert!(
        run.stderr.contains("overlaps another crop"),
        "{}",
        run.stderr
    );
    // The third crop completes it: bit for bit the full render, PNG too.
    assert!(go(&["--crop", "12,10,24,20", "-o", &out("p2.rtkfilm")]).ok);
    let parts = [out("p0.rtkfilm"), out("p1.rtkfilm"), out("p2.rtkfilm")];
    for ext in ["exr", "png"] {
        let m = out(&format!("m.{ext}"));
        let mut a = vec!["merge", m.as_str()];
        a.extend(parts.iter().map(String::as_str));
        let run = Run::from(rtk(&a).output().unwrap());
        assert!(run.ok, "{}", run.stderr);
    }
    assert_eq!(bits(&Image::read(&dir.path().join("m.exr"))), bits(&full));
    assert!(go(&["-o", &out("full.png")]).ok);
    assert_eq!(
        std::fs::read(dir.path().join("m.png")).unwrap(),
        std::fs::read(dir.path().join("full.png")).unwrap()
    );
}

#[test]
fn plugins_check_reports_broken_libraries() {
    let broken = plugin_folder(fixtures_dir(), &["notplugin", "abortplugin", "panicky"]);
    let other = plugin_folder(other_abi_dir(), &["otherabi"]);
    let run = Run::from(
        rtk(&[
            "plugins",
            "--check",
            "--plugin-path",
            broken.path().to_str().unwrap(),
            "--plugin-path",
            other.path().to_str().unwrap(),
        ])
        .output()
        .unwrap(),
    );
    assert!(!run.ok, "broken libraries must fail the check");
    let line = |class: &str| {
        run.stdout
            .lines()
            .find(|l| l.split_whitespace().nth(1) == Some(class))
            .unwrap_or_else(|| panic!("no line for {class}:\n{}", run.stdout))
            .to_string()
    };
    let l = line("notplugin");
    assert!(
        l.starts_with("broken") && l.contains("is not an rtk plugin"),
        "{l}"
    );
    let l = line("abortplugin");
    assert!(
        l.starts_with("broken") && l.contains("panic = \"abort\""),
        "{l}"
    );
    let l = line("otherabi");
    assert!(
        l.starts_with("broken") && l.contains("does not match this rtk's kernel records"),
        "{l}"
    );
    // A plugin whose create fails or panics still loads: healthy here.
    let l = line("panicky");
    assert!(l.starts_with("ok") && l.contains("[object]"), "{l}");
    let l = line("sphere");
    assert!(l.starts_with("ok") && l.contains("[object]"), "{l}");
    assert!(run.stdout.contains(", 3 broken"), "{}", run.stdout);
    assert!(run.stderr.contains("3 of"), "{}", run.stderr);

    // The built-in plugins alone are all healthy.
    let run = Run::from(rtk(&["plugins", "--check"]).output().unwrap());
    assert!(run.ok, "{}\n{}", run.stdout, run.stderr);
    assert!(!run.stdout.contains("broken  "), "{}", run.stdout);
}
