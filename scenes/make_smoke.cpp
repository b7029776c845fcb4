// Writes scenes/smoke.vdb, the density of scenes/smoke.toml: a rising plume (a column
// that widens and thins upwards, on a puff at its base) displaced by value-noise fBm.
// 36 x 60 x 36 voxels of 1/30 scene unit, half floats, Blosc, centred on the origin
// (x, z in ±0.6, y in ±1: a cube's [-1, 1]³ holds it). Build and run (Debian's libopenvdb-dev, as
// crates/lightpath/tests/data/vdb/make.sh):
//   g++ -O2 -std=c++17 scenes/make_smoke.cpp -o /tmp/make_smoke -lopenvdb -ltbb -lImath-3_1
//   (cd scenes && /tmp/make_smoke)
#include <openvdb/openvdb.h>
#include <openvdb/io/File.h>
#include <cmath>
#include <cstdint>
#include <iostream>

using namespace openvdb;

static float hash(int x, int y, int z) {
    uint32_t h = uint32_t(x) * 73856093u ^ uint32_t(y) * 19349663u ^ uint32_t(z) * 83492791u;
    h ^= h >> 13; h *= 0x5bd1e995u; h ^= h >> 15;
    return (h & 0xffffff) / float(0xffffff);
}

// Trilinear value noise in [0, 1] with a smoothstep fade.
static float noise(float x, float y, float z) {
    int ix = int(std::floor(x)), iy = int(std::floor(y)), iz = int(std::floor(z));
    float fx = x - ix, fy = y - iy, fz = z - iz;
    auto s = [](float t) { return t * t * (3 - 2 * t); };
    fx = s(fx); fy = s(fy); fz = s(fz);
    float v = 0;
    for (int c = 0; c < 8; ++c) {
        int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
        float w = (dx ? fx : 1 - fx) * (dy ? fy : 1 - fy) * (dz ? fz : 1 - fz);
        v += w * hash(ix + dx, iy + dy, iz + dz);
    }
    return v;
}

static float fbm(float x, float y, float z) {
    float v = 0, a = 0.5f, f = 1;
    for (int o = 0; o < 4; ++o, a *= 0.5f, f *= 2.03f) v += a * noise(x * f, y * f, z * f);
    return v / 0.9375f;
}

int main() {
    initialize();
    FloatGrid::Ptr g = FloatGrid::create(0.0f);
    g->setName("density");
    g->setGridClass(GRID_FOG_VOLUME);
    g->setSaveFloatAsHalf(true);
    const float h = 1.0f / 30.0f;
    g->setTransform(math::Transform::createLinearTransform(h));
    auto acc = g->getAccessor();
    for (int i = -18; i < 18; ++i)
        for (int j = -30; j < 30; ++j)
            for (int k = -18; k < 18; ++k) {
                float x = i * h, y = (j + 30) * h, z = k * h;  // from the plume's base, y up
                // The column's axis sways with height; its radius grows upwards.
                float ax = 0.08f * std::sin(3.0f * y), az = 0.06f * std::cos(2.3f * y);
                float r = std::hypot(x - ax, z - az);
                float radius = 0.12f + 0.22f * y;
                float n = fbm(x * 7 + 11, y * 5, z * 7 + 3);
                float column = 1.0f - r / (radius * (0.7f + 0.6f * n));
                float puff = 1.0f - std::hypot(x, (y - 0.2f) * 1.3f, z) / (0.3f * (0.75f + 0.5f * n));
                float d = std::max(column, puff);
                if (d <= 0) continue;
                // Thinner with height, wispy at the edges.
                float v = std::min(1.0f, 2.5f * d) * (1.0f - 0.6f * y / 2.0f) * (0.4f + 0.6f * n);
                if (v > 1e-3f) acc.setValue(Coord(i, j, k), v);
            }
    io::File f("smoke.vdb");
    f.setCompression(io::COMPRESS_BLOSC | io::COMPRESS_ACTIVE_MASK);
    f.write({g});
    f.close();
    std::cout << "smoke.vdb: " << g->activeVoxelCount() << " active voxels\n";
}
