"""Compares Lightpath's render of Blender's USD export (benches/usd/blender_shot.py) with
Cycles' render of the same file (the peers' cycles_file.py, one light group per light):
the beauty's mean, each light's share, and the alpha masks' intersection over union.

    python benches/usd/compare.py CYCLES.exr LIGHTPATH.exr    # Lightpath with --light-groups
"""

import sys

import numpy as np
import OpenEXR


def channels(path):
    out = {}
    with OpenEXR.File(path, separate_channels=True) as f:
        for part in f.parts:
            for name, ch in part.channels.items():
                out[name] = np.asarray(ch.pixels, dtype=np.float64)
    return out


def rgb(ch, prefix):
    return np.stack([ch[prefix + c] for c in "RGB"], axis=-1)


cy, lp = channels(sys.argv[1]), channels(sys.argv[2])
cy_prefix = next(k for k in cy if k.endswith("Combined.R"))[: -len("Combined.R")]
beauty_cy = rgb(cy, cy_prefix + "Combined.")
beauty_lp = rgb(lp, "")
print(f"beauty mean, Lightpath / Cycles: {beauty_lp.mean() / beauty_cy.mean():.3f}")
for light in sorted({k.split(".")[-2][len("Combined_"):] for k in cy if ".Combined_" in k}):
    theirs = rgb(cy, f"{cy_prefix}Combined_{light}.")
    name = "env_light" if light == "world" else light
    ours = rgb(lp, f"beauty_{name}.")
    share_cy = theirs.mean() / beauty_cy.mean()
    share_lp = ours.mean() / beauty_lp.mean()
    ratio = ours.mean(axis=(0, 1)) / np.maximum(theirs.mean(axis=(0, 1)), 1e-12)
    print(f"light {light}: share Lightpath {share_lp:.3f}, Cycles {share_cy:.3f}; "
          f"ratio R G B {ratio[0]:.3f} {ratio[1]:.3f} {ratio[2]:.3f}")
a_cy = cy.get(cy_prefix + "Combined.A")
if a_cy is not None and "A" in lp:
    m_cy, m_lp = a_cy > 0.5, lp["A"] > 0.5
    iou = (m_cy & m_lp).sum() / max((m_cy | m_lp).sum(), 1)
    print(f"alpha IoU: {iou:.4f}")
