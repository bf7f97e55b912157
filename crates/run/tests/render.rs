//! `colloidsim render`: pictures of spheres and of rods from GSD files, drawn atomically, never
//! over an existing picture without `force`, with bad options refused by name.

use colloidsim_particles::gsd::GsdWriter;
use colloidsim_particles::{Particles, SimBox};
use colloidsim_run::analyse::Frames;
use colloidsim_run::render::Colour;
use colloidsim_run::{Control, RenderOptions, RunOptions, Scenario, render};
use std::path::Path;

/// Width and height from a PNG's IHDR chunk.
fn png_size(path: &Path) -> (u32, u32) {
    let b = std::fs::read(path).unwrap();
    assert_eq!(
        &b[..8],
        b"\x89PNG\r\n\x1a\n",
        "{} is not a PNG",
        path.display()
    );
    let be = |k: usize| u32::from_be_bytes(b[k..k + 4].try_into().unwrap());
    (be(16), be(20))
}

/// Frames of a GIF: its graphic control extensions (one per frame as plotters writes them).
fn gif_frames(path: &Path) -> usize {
    let b = std::fs::read(path).unwrap();
    assert_eq!(&b[..6], b"GIF89a");
    b.windows(3).filter(|w| w == &[0x21, 0xF9, 0x04]).count()
}

/// Two frames of 60 spheres of two types in a ball of radius 3, in a box of edge 20.
fn spheres(dir: &Path) -> std::path::PathBuf {
    let path = dir.join("balls.gsd");
    let mut w = GsdWriter::create_new(&path).unwrap();
    let sbox = SimBox::new([20.0; 3]);
    for (step, s) in [(0u64, 1.0), (100, 0.8)] {
        let pos: Vec<[f64; 3]> = (0..60)
            .map(|i| {
                let t = i as f64 * 2.399_963;
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / 60.0;
                let r = (1.0 - z * z).sqrt() * 3.0 * s * (0.4 + 0.6 * (i % 3) as f64 / 2.0);
                [r * t.cos(), r * t.sin(), 3.0 * s * z]
            })
            .collect();
        let mut p = Particles::monodisperse(pos, 1.0);
        p.typeid = (0..60).map(|i| (i % 2) as u32).collect();
        p.diameter = (0..60)
            .map(|i| if i % 2 == 0 { 1.0 } else { 0.5 })
            .collect();
        p.type_names = vec!["big".into(), "small".into()];
        w.write_frame(step, &sbox, &p, false, &[]).unwrap();
    }
    path
}

fn files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn spheres_are_drawn_as_a_snapshot_and_an_animation() {
    let dir = tempfile::tempdir().unwrap();
    let gsd = spheres(dir.path());
    let snap = render(&gsd, &RenderOptions::default()).unwrap();
    assert_eq!(snap, dir.path().join("snapshot.png"));
    assert_eq!(png_size(&snap), (800, 600));
    let cut = render(
        &gsd,
        &RenderOptions {
            out: Some(dir.path().join("cut.png")),
            cut: true,
            colour: Colour::Distance,
            width: 400,
            frame: Some(0),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(png_size(&cut), (400, 300));
    let movie = render(
        &gsd,
        &RenderOptions {
            animate: true,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(gif_frames(&movie), 2);
    // No temporary file is left behind.
    assert_eq!(
        files(dir.path()),
        ["balls.gsd", "cut.png", "movie.gif", "snapshot.png"]
    );
}

#[test]
fn an_existing_picture_is_kept_without_force_and_bad_options_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let gsd = spheres(dir.path());
    let mine = dir.path().join("mine.png");
    std::fs::write(&mine, b"not colloidsim's").unwrap();
    let opts = RenderOptions {
        out: Some(mine.clone()),
        ..Default::default()
    };
    let e = render(&gsd, &opts).unwrap_err().to_string();
    assert!(e.contains("--force"), "{e}");
    assert_eq!(std::fs::read(&mine).unwrap(), b"not colloidsim's");
    render(
        &gsd,
        &RenderOptions {
            force: true,
            ..opts
        },
    )
    .unwrap();
    assert_eq!(png_size(&mine), (800, 600));
    for (o, named) in [
        (
            RenderOptions {
                width: 10,
                ..Default::default()
            },
            "--width",
        ),
        (
            RenderOptions {
                fps: 0,
                ..Default::default()
            },
            "--fps",
        ),
        (
            RenderOptions {
                frame: Some(2),
                ..Default::default()
            },
            "--frame",
        ),
        (
            RenderOptions {
                out: Some(dir.path().join("x.gif")),
                ..Default::default()
            },
            "--out",
        ),
        (
            RenderOptions {
                animate: true,
                frames: Frames {
                    first: 1,
                    last: Some(5),
                    stride: 1,
                },
                ..Default::default()
            },
            "--frames",
        ),
    ] {
        let e = render(&gsd, &o).unwrap_err().to_string();
        assert!(e.contains(named), "{named}: {e}");
    }
    assert!(!dir.path().join("x.gif").exists());
    let e = render(dir.path(), &RenderOptions::default()).unwrap_err();
    assert!(e.to_string().contains("no trajectory.gsd"), "{e}");
}

#[test]
fn rods_of_a_bcd_run_are_drawn_in_space_and_time() {
    let dir = tempfile::tempdir().unwrap();
    let sc = Scenario::from_toml(
        "method = \"bcd\"\nseed = 1\n[system]\nlength = 10.0\nparticles = 5\ndiameter = 0.5\n\
         [run]\ndt = 1e-3\ntime = 0.5\n[observe]\ntrajectory = { every = 50 }\n",
        dir.path(),
    )
    .unwrap();
    let out = dir.path().join("rods");
    colloidsim_run::run(
        &sc,
        &RunOptions {
            out: Some(out.clone()),
            seed: None,
            force: false,
        },
        &Control::default(),
    )
    .unwrap();
    let snap = render(&out, &RenderOptions::default()).unwrap();
    assert_eq!(png_size(&snap), (800, 600));
    let movie = render(
        &out,
        &RenderOptions {
            animate: true,
            frames: Frames {
                first: 0,
                last: None,
                stride: 2,
            },
            ..Default::default()
        },
    )
    .unwrap();
    // Frames 0, 50, ..., 500 of the run: 11 frames, every other one drawn.
    assert_eq!(gif_frames(&movie), 6);
}
