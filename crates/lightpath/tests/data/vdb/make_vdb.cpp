// Writes the OpenVDB test grids of crates/lightpath/src/scene/load/vdb.rs and
// crates/lightpath/src/media/grid.rs. Build and run with make.sh (Debian's libopenvdb-dev).
// Every density has a closed form the tests recompute: the ramp is
//   2 + i/4 + j/8 + k/16   for index coordinates (i, j, k) in [-4,11]x[0,9]x[2,9]
// (multiples of 1/16 below 16, exact in half floats), 0 elsewhere.
#include <openvdb/openvdb.h>
#include <openvdb/io/File.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <cmath>
#include <iostream>

using namespace openvdb;

static float ramp(const Coord& c) { return 2.0f + c.x() / 4.0f + c.y() / 8.0f + c.z() / 16.0f; }

static FloatGrid::Ptr make_ramp(const std::string& name) {
    FloatGrid::Ptr g = FloatGrid::create(0.0f);
    g->setName(name);
    g->setGridClass(GRID_FOG_VOLUME);
    auto acc = g->getAccessor();
    for (int i = -4; i <= 11; ++i)
        for (int j = 0; j <= 9; ++j)
            for (int k = 2; k <= 9; ++k) acc.setValue(Coord(i, j, k), ramp(Coord(i, j, k)));
    return g;
}

static void write(const std::string& path, GridPtrVec grids, uint32_t compression) {
    io::File f(path);
    f.setCompression(compression);
    f.write(grids);
    f.close();
    std::cout << path << ":";
    for (auto& g : grids) std::cout << " " << g->getName() << "(" << g->type() << ", "
                                    << g->transform().mapType() << ")";
    std::cout << "\n";
}

int main() {
    initialize();
    // Blosc (OpenVDB's default), a uniform scale and a translation.
    {
        auto g = make_ramp("density");
        auto t = math::Transform::createLinearTransform(0.1);
        t->postTranslate(Vec3d(1.0, 2.0, 3.0));
        g->setTransform(t);
        write("ramp.vdb", {g}, io::COMPRESS_BLOSC | io::COMPRESS_ACTIVE_MASK);
    }
    // Zlib, a non-uniform scale and a translation.
    {
        auto g = make_ramp("density");
        auto t = math::Transform::createLinearTransform(0.1);
        t->postScale(Vec3d(1.0, 2.0, 2.5));
        t->postTranslate(Vec3d(-1.0, 0.5, 0.0));
        g->setTransform(t);
        write("ramp_zip.vdb", {g}, io::COMPRESS_ZIP | io::COMPRESS_ACTIVE_MASK);
    }
    // Half floats (Blosc), a rotation: an affine map.
    {
        auto g = make_ramp("density");
        g->setSaveFloatAsHalf(true);
        math::Mat4d m = math::Mat4d::identity();
        m.preScale(Vec3d(0.2));
        m.postRotate(math::Z_AXIS, M_PI / 6.0);
        m.postTranslate(Vec3d(0.5, -0.25, 2.0));
        g->setTransform(math::Transform::createLinearTransform(m));
        write("ramp_half.vdb", {g}, io::COMPRESS_BLOSC | io::COMPRESS_ACTIVE_MASK);
    }
    // Tiles: a 128^3 tile of an internal node of the upper level (1.5), an 8^3 tile of
    // the lower level (3.0), and single voxels beside them in a leaf (4.0).
    {
        FloatGrid::Ptr g = FloatGrid::create(0.0f);
        g->setName("density");
        g->fill(CoordBBox(Coord(0), Coord(127)), 1.5f, true);
        g->fill(CoordBBox(Coord(128, 0, 0), Coord(135, 7, 7)), 3.0f, true);
        g->tree().setValue(Coord(136, 0, 0), 4.0f);
        g->tree().setValue(Coord(137, 1, 2), 4.0f);
        write("tiles.vdb", {g}, io::COMPRESS_BLOSC | io::COMPRESS_ACTIVE_MASK);
    }
    // Several grids: two floats, a vector grid, a level set and a double grid; one root
    // node each (8 KB of masks apiece).
    {
        FloatGrid::Ptr d = FloatGrid::create(0.0f);
        d->setName("density");
        d->tree().setValue(Coord(1, 1, 1), 0.75f);
        FloatGrid::Ptr temp = FloatGrid::create(0.0f);
        temp->setName("temperature");
        temp->tree().setValue(Coord(1, 2, 3), 300.0f);
        Vec3SGrid::Ptr v = Vec3SGrid::create(Vec3s(0.0f));
        v->setName("velocity");
        v->tree().setValue(Coord(0, 0, 0), Vec3s(1.0f, 2.0f, 3.0f));
        auto ls = tools::createLevelSetSphere<FloatGrid>(2.0f, Vec3f(3.0f), 0.5f, 2.0f);
        ls->setName("surface");
        DoubleGrid::Ptr dbl = DoubleGrid::create(0.0);
        dbl->setName("double");
        dbl->tree().setValue(Coord(0, 0, 0), 1.0);
        write("grids.vdb", {d, temp, v, ls, dbl}, io::COMPRESS_BLOSC | io::COMPRESS_ACTIVE_MASK);
    }
    // A puff for heterogeneous media in scenes (tests/it/media.rs): 2 exp(-|p|^2 / 0.18)
    // at voxel centres p = 0.1 (i, j, k), i, j, k in [-8, 7], centred on the origin.
    {
        FloatGrid::Ptr g = FloatGrid::create(0.0f);
        g->setName("density");
        g->setGridClass(GRID_FOG_VOLUME);
        g->setTransform(math::Transform::createLinearTransform(0.1));
        auto acc = g->getAccessor();
        for (int i = -8; i <= 7; ++i)
            for (int j = -8; j <= 7; ++j)
                for (int k = -8; k <= 7; ++k) {
                    double r2 = 0.01 * (i * i + j * j + k * k);
                    acc.setValue(Coord(i, j, k), float(2.0 * std::exp(-r2 / 0.18)));
                }
        write("puff.vdb", {g}, io::COMPRESS_BLOSC | io::COMPRESS_ACTIVE_MASK);
    }
    return 0;
}
