"""Equiangular sampling towards small area lights (integrator/volume.rs) against free
flights alone, on the scenes in equiangular/ (their lights hidden from the camera, so
the error is the medium's and the surfaces'): RMSE per pixel and channel against a
reference (the mean of one high-spp render of each estimator, both unbiased), at equal
samples and at equal time (RMSE scaled by the square root of the CPU time ratio,
RMSE ∝ 1/√t), and the same for the mean absolute error, which a few fireflies sway
less (both estimators have some where flights graze a light: its area sampling's 1/d²).
Each render is one thread, timed by the CPU time it used, so other work on
the machine changes the times little. `volume_sampling = "distance"` is what Lightpath
did for these scenes before (area lights took no equiangular sampling; without point or
spot lights no flight sampled equiangularly).

    cargo build -p lightpath
    python3 benches/media/equiangular.py --spp 64 --ref-spp 2048 --repeat 5
    python3 benches/media/compare.py --spp 1 --mitsuba-spp 1   # writes the fog box scene
    python3 benches/media/equiangular.py --scenes benches/media/out/fog_cornell_beauty.toml

Every render is 96×96 (`--resolution`).

It needs numpy and mitsuba (to read the EXRs).
"""

import argparse
import os
import resource
import subprocess

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
SCENES = ["fog_sphere", "fog_quad", "fog_disk_heldout"]


def load(path):
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    return np.array(mi.Bitmap(path)).astype(np.float64)[..., :3]


def render(binary, scene, mode, spp, seed, out):
    """Renders and returns (image, CPU seconds)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    path = scene if scene.endswith(".toml") else os.path.join(HERE, "equiangular",
                                                               scene + ".toml")
    subprocess.run([binary, "render", path, "--resolution", "96x96", "--spp", str(spp), "--seed", str(seed), "--volume-sampling", mode,
                    "--aovs", "none", "--threads", "1", "--no-open", "-o", out],
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return load(out), cpu


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--binary", default=os.path.join(HERE, "../../target/debug/lightpath"))
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--ref-spp", type=int, default=2048)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--scenes", nargs="*", default=SCENES)
    ap.add_argument("--out", default=os.path.join(HERE, "out", "equiangular"))
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    for scene in args.scenes:
        name = os.path.basename(scene).removesuffix(".toml")
        refs = []
        for mode in ("mis", "distance"):
            path = os.path.join(args.out, f"{name}_{mode}_{args.ref_spp}.exr")
            if os.path.exists(path):
                refs.append(load(path))
            else:
                refs.append(render(args.binary, scene, mode, args.ref_spp, 1000, path)[0])
        ref = (refs[0] + refs[1]) / 2
        # The two references differ by noise only (both unbiased): their RMSE against
        # each other bounds how well the reference resolves the errors below.
        ref_noise = float(np.sqrt(np.mean((refs[0] - refs[1]) ** 2))) / 2
        rows = []
        for run in range(args.repeat):
            row = {}
            for mode in ("mis", "distance"):
                out = os.path.join(args.out, f"{name}_{mode}_{args.spp}.exr")
                img, cpu = render(args.binary, scene, mode, args.spp, run + 1, out)
                row[mode] = (float(np.sqrt(np.mean((img - ref) ** 2))), cpu,
                             float(np.mean(np.abs(img - ref))))
            rows.append(row)
        print(f"{name} ({args.spp} spp, reference {args.ref_spp} spp per estimator, "
              f"its noise ≈ {ref_noise:.2e}; reference means {refs[0].mean():.4f} "
              f"mis, {refs[1].mean():.4f} distance)")
        for i, row in enumerate(rows):
            (em, tm, _), (ed, td, _) = row["mis"], row["distance"]
            print(f"  run {i}: mis RMSE {em:.4e} in {tm:.1f} s, distance {ed:.4e} in "
                  f"{td:.1f} s; equal spp {em / ed:.3f}, equal time "
                  f"{em * np.sqrt(tm / td) / ed:.3f}")
        # Over runs: the root of the mean squared error (fireflies make single runs'
        # RMSE spread widely).
        em = np.sqrt(np.mean([r["mis"][0] ** 2 for r in rows]))
        ed = np.sqrt(np.mean([r["distance"][0] ** 2 for r in rows]))
        tm = np.mean([r["mis"][1] for r in rows])
        td = np.mean([r["distance"][1] for r in rows])
        am = np.mean([r["mis"][2] for r in rows])
        ad = np.mean([r["distance"][2] for r in rows])
        print(f"  over runs: RMSE equal spp {em / ed:.3f}, equal time "
              f"{em * np.sqrt(tm / td) / ed:.3f}; mean absolute error (fireflies weigh "
              f"less) equal spp {am / ad:.3f}, equal time {am * np.sqrt(tm / td) / ad:.3f}; "
              f"CPU time mis / distance {tm / td:.2f}")


if __name__ == "__main__":
    main()
