//! Agreement with the peer: `cornell-classic` against Mitsuba 3's 65536-spp render of the
//! same scene (`benches/peer/ref/cornell_ref.exr`, made by `benches/peer/run.sh --reference`).

use lightpath::aov;
use lightpath::{render, RenderOptions, Scene};

fn render_classic(spp: u32, seed: u64) -> [Vec<f32>; 3] {
    let src = lightpath::load_source("cornell-classic").unwrap();
    let mut desc = src.parse().unwrap();
    desc.render.seed = seed;
    let scene = Scene::build(&desc, &aov::assemble(vec![])).unwrap();
    let (film, _) = render(
        &scene,
        &RenderOptions {
            spp,
            first_sample: 0,
        },
    );
    [film.channel(0, 0), film.channel(0, 1), film.channel(0, 2)]
}

#[test]
fn cornell_classic_agrees_with_the_mitsuba_reference() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../benches/peer/ref/cornell_ref.exr"
    );
    let reference = lightpath::output::read_exr(std::path::Path::new(path)).unwrap();
    assert_eq!((reference.width, reference.height), (256, 256));
    let refs = ["R", "G", "B"].map(|c| reference.channel(c).unwrap().to_vec());

    // Two independent half renders: their difference measures our own noise.
    let spp = 8;
    let a = render_classic(spp, 1);
    let b = render_classic(spp, 2);
    for c in 0..3 {
        let n = refs[c].len() as f64;
        let ours: Vec<f64> = a[c]
            .iter()
            .zip(&b[c])
            .map(|(x, y)| 0.5 * (*x as f64 + *y as f64))
            .collect();
        let mean_ours = ours.iter().sum::<f64>() / n;
        let mean_ref = refs[c].iter().map(|v| *v as f64).sum::<f64>() / n;
        assert!(
            (mean_ours - mean_ref).abs() <= 0.01 * mean_ref,
            "channel {c}: mean {mean_ours} vs reference {mean_ref}"
        );
        // E[(a - b)²] = 2σ²/spp per pixel, so the combined render's expected squared
        // error against an exact image is mean((a - b)²) / 4.
        let predicted = a[c]
            .iter()
            .zip(&b[c])
            .map(|(x, y)| ((x - y) as f64).powi(2))
            .sum::<f64>()
            / n
            / 4.0;
        let mse = ours
            .iter()
            .zip(&refs[c])
            .map(|(o, r)| (o - *r as f64).powi(2))
            .sum::<f64>()
            / n;
        eprintln!(
            "channel {c}: mean {mean_ours:.5} vs {mean_ref:.5}, RMSE {:.5}, predicted by noise {:.5}",
            mse.sqrt(),
            predicted.sqrt()
        );
        // The reference's own noise (65536 spp) adds under 0.1% of ours at 16 spp; allow
        // 15% for the spread of the variance estimate itself.
        assert!(
            mse <= 1.15 * predicted,
            "channel {c}: RMSE {:.5} against the reference, noise alone predicts {:.5}",
            mse.sqrt(),
            predicted.sqrt()
        );
    }
}
