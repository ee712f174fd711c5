//! Fuzzing the readers of outside data (issue 25 item 2): each target of
//! `rtk_host::fuzzing` gets mutated seeds and random bytes, and must answer
//! every input (accept or refuse) without a panic and within a second.
//!
//! The mutator is structure-unaware and coverage-blind (byte flips,
//! interesting values, inserts, deletions, duplicated and spliced ranges,
//! truncations over valid seeds): the toolchain here is stable Rust, and a
//! coverage-guided fuzzer (cargo-fuzz, cargo-afl) is not set up yet. The
//! default run takes a few thousand inputs per target; the long run
//! (`fuzz_readers_long`, ignored) takes `RTK_FUZZ_INPUTS` per target and
//! prints the table BENCHMARKS.md quotes.

use rtk_host::fuzzing::{film_seed, image_seeds, Target, SET_BASE, TARGETS};
use rtk_kernel::RngState;
use rtk_tests::root;
use std::time::{Duration, Instant};

/// The seeds of a target: valid inputs it accepts.
fn seeds(name: &str) -> Vec<Vec<u8>> {
    match name {
        "scene-toml" => [
            "cornell",
            "default",
            "instances",
            "csg",
            "motion",
            "materials",
        ]
        .iter()
        .map(|s| std::fs::read(root().join(format!("scenes/{s}.toml"))).unwrap())
        .chain([SET_BASE.as_bytes().to_vec()])
        .collect(),
        "set-overrides" => vec![
            b"render.spp=4\nobjects.ball.radius=2.0".to_vec(),
            b"render.background=[0.1, 0.2, 0.3]\nrender.filter=\"gaussian\"".to_vec(),
            b"objects.world.children=[\"ball\", { object = \"ball\", transform = { scale = 2 } }]"
                .to_vec(),
            b"render.shutter=[0.0, 0.5]\nrender.origin=\"world\"".to_vec(),
        ],
        "ray-file" => {
            let ray = |o: [f32; 3], d: [f32; 3]| -> Vec<u8> {
                o.iter()
                    .chain(&d)
                    .chain(&[0.0, f32::INFINITY])
                    .flat_map(|v| v.to_le_bytes())
                    .collect()
            };
            vec![
                ray([0.0; 3], [0.0, 0.0, 1.0]),
                [
                    ray([1.0, 2.0, 3.0], [0.0, -1.0, 0.0]),
                    ray([-5.0; 3], [1.0; 3]),
                ]
                .concat(),
            ]
        }
        "film-file" => vec![film_seed(3, 2), film_seed(1, 1)],
        "pfm-image" => vec![image_seeds().0],
        "npy-image" => vec![image_seeds().1],
        // Golden translations that need no other file (an include or a
        // mesh would be absent beside the fuzzer's file).
        "mitsuba-xml" => vec![
            include_str!("../../shell/import/tests/golden/default_param.xml"),
            include_str!("../../shell/import/tests/golden/emitter_point_to_world.xml"),
            include_str!("../../shell/import/tests/golden/integrator_moment.xml"),
            include_str!("../../shell/import/tests/golden/sensor_rigid.xml"),
            include_str!("../../shell/import/tests/golden/ref.xml"),
            include_str!("../../shell/import/tests/golden/alias.xml"),
        ]
        .into_iter()
        .map(|s: &str| s.as_bytes().to_vec())
        .collect(),
        other => panic!("no seeds for {other}"),
    }
}

const INTERESTING: [u8; 10] = [0, 1, 0x7f, 0x80, 0xff, b'[', b'"', b'=', b'\n', b'.'];

/// A mutation of one seed (or of random bytes), as a fuzzer's havoc stage does.
fn mutate(rng: &mut RngState, seeds: &[Vec<u8>]) -> Vec<u8> {
    let pick =
        |rng: &mut RngState, n: usize| (rng.next_f32() as f64 * n as f64) as usize % n.max(1);
    if rng.next_f32() < 0.05 {
        let n = pick(rng, 256);
        return (0..n).map(|_| pick(rng, 256) as u8).collect();
    }
    let mut b = seeds[pick(rng, seeds.len())].clone();
    for _ in 0..1 + pick(rng, 8) {
        let len = b.len();
        let at = pick(rng, len + 1);
        match pick(rng, 7) {
            0 if len > 0 => b[at.min(len - 1)] ^= 1 << pick(rng, 8),
            1 if len > 0 => b[at.min(len - 1)] = INTERESTING[pick(rng, INTERESTING.len())],
            2 => b.insert(at, pick(rng, 256) as u8),
            3 if len > 0 => {
                let end = (at + 1 + pick(rng, 16)).min(len);
                b.drain(at.min(len - 1)..end);
            }
            4 if len > 0 => {
                let (s, n) = (pick(rng, len), 1 + pick(rng, 32));
                let piece: Vec<u8> = b[s..(s + n).min(len)].to_vec();
                b.splice(at..at, piece);
            }
            5 => {
                let other = &seeds[pick(rng, seeds.len())];
                let s = pick(rng, other.len());
                let piece = other[s..(s + 1 + pick(rng, 64)).min(other.len())].to_vec();
                b.splice(at..at, piece);
            }
            _ => b.truncate(at),
        }
    }
    b
}

/// What one target's run found.
struct Found {
    inputs: u64,
    accepted: u64,
    panics: Vec<Vec<u8>>,
    slowest: Duration,
    seconds: f64,
}

fn fuzz(t: &Target, inputs: u64, seed: u64) -> Found {
    let seeds = seeds(t.name);
    for s in &seeds {
        assert!(
            (t.read)(s).is_ok(),
            "{}: a seed is refused: {:?}",
            t.name,
            (t.read)(s)
        );
    }
    let mut rng = RngState::seeded(seed);
    let mut found = Found {
        inputs,
        accepted: 0,
        panics: vec![],
        slowest: Duration::ZERO,
        seconds: 0.0,
    };
    let start = Instant::now();
    for _ in 0..inputs {
        let input = mutate(&mut rng, &seeds);
        let t0 = Instant::now();
        match std::panic::catch_unwind(|| (t.read)(&input)) {
            Ok(Ok(())) => found.accepted += 1,
            Ok(Err(_)) => {}
            Err(_) if found.panics.len() < 5 => found.panics.push(input),
            Err(_) => {}
        }
        found.slowest = found.slowest.max(t0.elapsed());
    }
    found.seconds = start.elapsed().as_secs_f64();
    found
}

/// Every target, each on a thread of its own (the panic hook silenced
/// meanwhile: the panics are counted, not printed); the table's rows.
fn check_all(inputs: u64) -> Vec<String> {
    let quiet = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let found: Vec<Found> = std::thread::scope(|s| {
        let runs: Vec<_> = (TARGETS.iter().enumerate())
            .map(|(i, t)| s.spawn(move || fuzz(t, inputs, 0x5eed + i as u64)))
            .collect();
        runs.into_iter().map(|r| r.join().unwrap()).collect()
    });
    std::panic::set_hook(quiet);
    let mut rows = vec![];
    for (t, f) in TARGETS.iter().zip(found) {
        assert!(
            f.panics.is_empty(),
            "{}: {} inputs panicked, e.g. {:?}",
            t.name,
            f.panics.len(),
            String::from_utf8_lossy(&f.panics[0])
        );
        assert!(
            f.slowest < Duration::from_secs(1),
            "{}: an input took {:?}",
            t.name,
            f.slowest
        );
        rows.push(format!(
            "| {} | {} | {} | 0 | {:.1} ms | {:.0} |",
            t.name,
            f.inputs,
            f.accepted,
            f.slowest.as_secs_f64() * 1e3,
            f.inputs as f64 / f.seconds
        ));
    }
    rows
}

#[test]
fn fuzz_readers_short() {
    check_all(3000);
}

#[test]
#[ignore = "minutes: RTK_FUZZ_INPUTS inputs per reader (default 1,000,000)"]
fn fuzz_readers_long() {
    let n = std::env::var("RTK_FUZZ_INPUTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1_000_000);
    let rows = check_all(n);
    println!("| reader | inputs | accepted | panics | slowest input | inputs/s |");
    println!("|---|---:|---:|---:|---:|---:|");
    for r in rows {
        println!("{r}");
    }
}
