//! The scene parser and checker on arbitrary and mutated text: they may
//! refuse anything, but never panic, and every refusal is shown on one
//! terminal-safe line (no control character but the notes' line breaks).

use proptest::prelude::*;
use rtk_shell::{Desc, SceneFile};
use std::path::Path;

const GOOD: &str = r#"[render]
width = 8
height = 8
root = "world"
background = [0.1, 0.2, 0.3]
integrator = { class = "whitted", max_depth = 4 }

[cameras.main]
class = "pinhole"
eye = [0.0, 0.0, 5.0]

[lights.sun]
class = "directional"
direction = [0.0, -1.0, 0.0]
irradiance = [1.0, 1.0, 1.0]

[shaders.red]
class = "lambert"
albedo = [0.8, 0.1, 0.1]

[objects.ball]
class = "sphere"
radius = 1.0

[objects.bunny]
class = "mesh"
file = "meshes/bunny.ply"
accel = "octree"

[objects.world]
class = "list"
children = [
  "ball",
  { object = "bunny", shader = "red", attributes = { albedo = [0.1, 0.8, 0.1] },
    transform = [{ scale = 2.0 }, { rotate = { axis = [0, 1, 0], angle = 30 } }, { translate = [1, 0, 0] }] },
  { object = "ball", transform = { matrix = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0] } },
]
"#;

/// Parse and check `text`; a refusal must display safely.
fn check(text: &str, sets: &[String]) {
    let mut file = match SceneFile::parse(Path::new("fuzz.toml"), text.to_string()) {
        Ok(f) => f,
        Err(e) => return shown_safely(&e.to_string()),
    };
    if let Err(e) = file.apply_overrides(sets) {
        return shown_safely(&e.to_string());
    }
    if let Err(e) = Desc::from_file(&file) {
        shown_safely(&e.to_string());
    }
}

fn shown_safely(msg: &str) {
    assert!(
        !msg.chars().any(|c| c.is_control() && c != '\n'),
        "control character in {msg:?}"
    );
}

/// `GOOD` with characters replaced, removed or inserted.
fn mutated(edits: &[(usize, u8, char)]) -> String {
    let mut s: Vec<char> = GOOD.chars().collect();
    for &(at, kind, c) in edits {
        let at = at % (s.len() + 1);
        match kind % 3 {
            0 if at < s.len() => s[at] = c,
            1 if at < s.len() => {
                s.remove(at);
            }
            _ => s.insert(at, c),
        }
    }
    s.into_iter().collect()
}

/// Characters that matter to TOML and to the shell, and some that do not.
fn toml_char() -> impl Strategy<Value = char> {
    prop_oneof![
        prop::sample::select(vec![
            '[', ']', '{', '}', '"', '\'', '=', ',', '.', '\n', '#', '-', '+', 'e', '0', '9', ' ',
            '\u{1b}', '\u{0}', 'é', '\\'
        ]),
        any::<char>(),
    ]
}

#[test]
fn the_seed_is_a_good_scene() {
    let file = SceneFile::parse(Path::new("fuzz.toml"), GOOD.to_string()).unwrap();
    Desc::from_file(&file).unwrap();
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_text_never_panics(text in ".{0,400}") {
        check(&text, &[]);
    }

    #[test]
    fn toml_like_text_never_panics(chars in proptest::collection::vec(toml_char(), 0..300)) {
        check(&chars.into_iter().collect::<String>(), &[]);
    }

    #[test]
    fn mutated_scenes_never_panic(
        edits in proptest::collection::vec((any::<usize>(), any::<u8>(), toml_char()), 1..8)
    ) {
        check(&mutated(&edits), &[]);
    }

    #[test]
    fn overrides_never_panic(
        key in "(render|cameras|lights|shaders|objects|x)(\\.[a-z_\\[\\]0-9]{0,8}){0,4}",
        value in ".{0,40}",
    ) {
        check(GOOD, &[format!("{key}={value}")]);
    }
}
