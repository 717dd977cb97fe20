//! The sweep-painting designer (issue 23; seed 002, 4.3): a kiwi-like
//! block from a radial section, a skin and 100 seeds; the seeds where the
//! file put them, the section swept, the skin on the outer face, the same
//! bytes for the same seed, and bad input refused clearly.

use organtex::synth::sweep::{InclusionFile, SweepOptions, inclusions, kiwi_example, sweep};

#[test]
fn a_kiwi_block_has_its_seeds_where_the_file_put_them() {
    let (section, skin, file) = kiwi_example();
    let n = 128;
    let incs = inclusions(&file, n, std::path::Path::new(".")).expect("inclusions");
    let opts = SweepOptions {
        size: n,
        axis: 2,
        noise: 0.0,
        seed: 0,
    };
    let block = sweep(&section, Some((&skin, 4)), &incs, &opts).expect("sweep");
    for (k, s) in file.inclusions.iter().enumerate() {
        let [x, y, z] = s.centre.map(|c| (c * n as f64) as usize);
        assert_eq!(
            block.voxels[block.index(x, y, z)],
            s.colour.expect("a colour"),
            "seed {k} at {:?}",
            s.centre
        );
    }
    // Away from seeds and skin, the block is the section, swept: the same
    // colour at every z.
    let (x, y) = (64, 70);
    let first = block.voxels[block.index(x, y, 0)];
    assert!((0..n).all(|z| block.voxels[block.index(x, y, z)] == first));
    assert_eq!(first, section.pixels[y * 128 + x]);
    // The skin covers the outer face, y < 4, and only that.
    let brownish = |c: [u8; 3]| c[0] > c[1] && c[1] > c[2] && c[2] == 40;
    assert!((0..n).all(|x| brownish(block.voxels[block.index(x, 1, 7)])));
    assert!(!brownish(block.voxels[block.index(64, 64, 7)]));

    // Noise displaces the sweep, deterministically.
    let noisy = |seed| {
        sweep(
            &section,
            None,
            &[],
            &SweepOptions {
                noise: 2.0,
                seed,
                ..opts.clone()
            },
        )
        .expect("noisy")
    };
    let (a, b) = (noisy(1), noisy(1));
    assert_eq!(a, b);
    assert_ne!(a, noisy(2));
    let varies = (0..n)
        .filter(|&z| a.voxels[a.index(40, 70, z)] != a.voxels[a.index(40, 70, 0)])
        .count();
    assert!(
        varies > 10,
        "noise changes the section along the axis ({varies})"
    );
}

#[test]
fn bad_sweep_input_gives_clear_errors() {
    let dir = tempfile::tempdir().expect("tempdir");
    let exe = env!("CARGO_BIN_EXE_organtex");
    let section = dir.path().join("section.png");
    image::RgbImage::from_pixel(64, 64, image::Rgb([90, 160, 40]))
        .save(&section)
        .expect("png");
    let run = |args: &[&str]| {
        let out = std::process::Command::new(exe)
            .args(args)
            .output()
            .expect("run");
        (
            out.status.success(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let out = dir.path().join("b.nrrd");
    let out_s = out.to_str().expect("utf-8");
    // An inclusion file with a bad key.
    let spec = dir.path().join("seeds.toml");
    std::fs::write(
        &spec,
        "[[inclusion]]\ncentre = [0.5, 0.5, 0.5]\nradius = [0.1, 0.1, 0.1]\ncolour = [0, 0, 0]\n",
    )
    .expect("write");
    let (ok, err) = run(&[
        "sweep",
        section.to_str().expect("utf-8"),
        "--size",
        "64",
        "--inclusions",
        spec.to_str().expect("utf-8"),
        "-o",
        out_s,
    ]);
    assert!(
        !ok && err.contains("seeds.toml") && err.contains("radius"),
        "{err}"
    );
    // A section whose size does not fit: not square.
    let wide = dir.path().join("wide.png");
    image::RgbImage::from_pixel(96, 64, image::Rgb([9, 9, 9]))
        .save(&wide)
        .expect("png");
    let (ok, err) = run(&[
        "sweep",
        wide.to_str().expect("utf-8"),
        "--size",
        "64",
        "-o",
        out_s,
    ]);
    assert!(
        !ok && err.contains("wide.png") && err.contains("square"),
        "{err}"
    );
    // Too small for the block.
    let (ok, err) = run(&[
        "sweep",
        section.to_str().expect("utf-8"),
        "--size",
        "256",
        "-o",
        out_s,
    ]);
    assert!(!ok && err.contains("at least 128 pixels"), "{err}");
    assert!(!out.exists(), "nothing written");
    // A good one writes a block whose header names its depth axis.
    let (ok, err) = run(&[
        "sweep",
        section.to_str().expect("utf-8"),
        "--size",
        "32",
        "-o",
        out_s,
    ]);
    assert!(ok, "{err}");
    let (v, depth) = organtex::synth::volume::Volume::read_nrrd_with_depth(&out).expect("read");
    assert_eq!((v.size, depth), ([32; 3], Some(1)));
    let _: InclusionFile = toml::from_str("").expect("an empty file is no inclusions");
}
