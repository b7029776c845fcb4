"""EXR reading and pixel masks shared by the bench scripts (numpy and the OpenEXR module).

A script in benches/<topic>/ imports it with

    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    from benchlib.exr import channels, rgb
"""

import numpy as np
import OpenEXR


def channels(path, header=None):
    """Every channel of every part as float64 arrays, by stored name (`R`, `diffuse.G`,
    `ViewLayer.Combined.B`). If `header` is a dict, each part's header is merged into it."""
    out = {}
    with OpenEXR.File(path, separate_channels=True) as f:
        for part in f.parts:
            if header is not None:
                header.update(part.header)
            for name, ch in part.channels.items():
                out[name] = np.asarray(ch.pixels, dtype=np.float64)
    return out


def rgb(ch, prefix=""):
    """The (h, w, 3) image of channels `prefix`R, G and B: prefix "" is Lightpath's beauty,
    "diffuse." an AOV, "ViewLayer.Combined." a Cycles pass."""
    missing = [prefix + c for c in "RGB" if prefix + c not in ch]
    if missing:
        raise KeyError(f"no channels {missing} (has {sorted(ch)[:12]}...)")
    return np.stack([ch[prefix + c] for c in "RGB"], axis=-1)


def luminance(x):
    """Rec. 709 luminance of an (..., 3) image."""
    return x @ np.array([0.2126, 0.7152, 0.0722])


def erode(mask, n=1):
    """`mask` shrunk by `n` pixels (4-neighbourhood): keeps object masks off the silhouette,
    where the renderers' pixel filters differ."""
    for _ in range(n):
        m = mask.copy()
        m[1:, :] &= mask[:-1, :]
        m[:-1, :] &= mask[1:, :]
        m[:, 1:] &= mask[:, :-1]
        m[:, :-1] &= mask[:, 1:]
        mask = m
    return mask
