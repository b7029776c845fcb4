"""Writes a .glb of one N×N grid mesh (2·N² triangles) with normals and UVs, lit by one
point light and seen by one camera, for the load-time and memory figures of
docs/performance.md:

    python benches/gltf/make_grid.py 708 grid.glb      # ~1M triangles
    python benches/gltf/make_grid.py 708 bare.glb bare # the same without normals and UVs
    /usr/bin/time -v lightpath render grid.glb --spp 1 --resolution 16x16 --aovs none

Needs numpy only.
"""

import json
import struct
import sys

import numpy as np

n = int(sys.argv[1])
out = sys.argv[2]
# "bare": positions and indices only (no normals, no UVs), to isolate their cost.
bare = len(sys.argv) > 3 and sys.argv[3] == "bare"

u = np.linspace(0.0, 1.0, n + 1, dtype=np.float32)
uu, vv = np.meshgrid(u, u)
pos = np.stack([uu * 10 - 5, np.sin(uu * 20) * 0.2, vv * 10 - 5], -1).reshape(-1, 3)
nrm = np.tile(np.array([0, 1, 0], np.float32), (pos.shape[0], 1))
uv = np.stack([uu, vv], -1).reshape(-1, 2).astype(np.float32)
i = np.arange(n, dtype=np.uint32)
a = (i[None, :] + i[:, None] * (n + 1)).reshape(-1)
idx = np.stack([a, a + n + 1, a + 1, a + 1, a + n + 1, a + n + 2], -1).reshape(-1).astype(np.uint32)

blobs = [pos.astype(np.float32).tobytes(), nrm.tobytes(), uv.tobytes(), idx.tobytes()]
views, offset = [], 0
for b in blobs:
    views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(b)})
    offset += len(b)
bin_data = b"".join(blobs)
count = pos.shape[0]
doc = {
    "asset": {"version": "2.0"},
    "scene": 0,
    "scenes": [{"nodes": [0, 1, 2]}],
    "nodes": [
        {"name": "grid", "mesh": 0},
        {"name": "cam", "camera": 0, "translation": [0, 8, 8], "rotation": [-0.3826834, 0, 0, 0.9238795]},
        {"name": "key", "translation": [0, 5, 0], "extensions": {"KHR_lights_punctual": {"light": 0}}},
    ],
    "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}],
    "extensionsUsed": ["KHR_lights_punctual"],
    "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 5000}]}},
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0} if bare else
                                {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}, "indices": 3}]}],
    "accessors": [
        {"bufferView": 0, "componentType": 5126, "count": count, "type": "VEC3",
         "min": pos.min(0).tolist(), "max": pos.max(0).tolist()},
        {"bufferView": 1, "componentType": 5126, "count": count, "type": "VEC3"},
        {"bufferView": 2, "componentType": 5126, "count": count, "type": "VEC2"},
        {"bufferView": 3, "componentType": 5125, "count": len(idx), "type": "SCALAR"},
    ],
    "bufferViews": views,
    "buffers": [{"byteLength": len(bin_data)}],
}
js = json.dumps(doc).encode()
js += b" " * (-len(js) % 4)
bin_data += b"\0" * (-len(bin_data) % 4)
with open(out, "wb") as f:
    f.write(b"glTF" + struct.pack("<II", 2, 12 + 8 + len(js) + 8 + len(bin_data)))
    f.write(struct.pack("<I", len(js)) + b"JSON" + js)
    f.write(struct.pack("<I", len(bin_data)) + b"BIN\0" + bin_data)
print(f"{out}: {len(idx) // 3} triangles")
