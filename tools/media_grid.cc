// The media benchmark's OpenVDB helper, built by hand against libopenvdb-dev (not part of the
// product's build; tools/media_bench.sh builds it):
//
//   g++ -std=c++20 -O2 tools/media_grid.cc -o media_grid -lopenvdb -ltbb -lImath
//
//   media_grid info FILE.vdb       every grid: name, type, precision on disk, background, active
//                                  voxels, bounding box, transform, metadata; one line of totals
//   media_grid smoke OUT.vdb N     a procedural N^3 smoke: fractal value noise inside a sphere,
//                                  grid "density", voxel size 2/N (a 2 m cube about the origin),
//                                  Blosc-compressed float, the same bits on every run
#include <openvdb/openvdb.h>
#include <openvdb/tools/Count.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace {

int Info(const std::string& path) {
    openvdb::io::File file(path);
    file.open(/*delayLoad=*/false);
    // Each grid's compression is in its metadata (file_compression), as OpenVDB wrote it.
    std::printf("file %s: %ju bytes, library %s, file format %u\n", path.c_str(),
                uintmax_t(std::filesystem::file_size(path)), file.version().c_str(),
                file.fileVersion());
    const openvdb::MetaMap::Ptr file_meta = file.getMetadata();
    for (auto it = file_meta->beginMeta(); it != file_meta->endMeta(); ++it) {
        std::printf("  file meta %s (%s) = %s\n", it->first.c_str(), it->second->typeName().c_str(),
                    it->second->str().c_str());
    }
    openvdb::Index64 total_active = 0;
    openvdb::GridPtrVecPtr grids = file.getGrids();
    for (const openvdb::GridBase::Ptr& grid : *grids) {
        const openvdb::CoordBBox box = grid->evalActiveVoxelBoundingBox();
        const openvdb::Index64 active = grid->activeVoxelCount();
        total_active += active;
        std::printf("grid \"%s\": %s, value type %s, class %s, saved as %s, %ju active voxels",
                    grid->getName().c_str(), grid->type().c_str(), grid->valueType().c_str(),
                    openvdb::GridBase::gridClassToString(grid->getGridClass()).c_str(),
                    grid->saveFloatAsHalf() ? "half" : "full", uintmax_t(active));
        if (active > 0) {
            std::printf(", active box [%d %d %d]..[%d %d %d]", box.min().x(), box.min().y(),
                        box.min().z(), box.max().x(), box.max().y(), box.max().z());
        }
        std::printf("\n");
        if (auto f = openvdb::GridBase::grid<openvdb::FloatGrid>(grid)) {
            float lo = 0, hi = 0;
            if (active > 0) {
                const auto mm = openvdb::tools::minMax(f->tree());
                lo = mm.min(), hi = mm.max();
            }
            std::printf("  background %g, active values in [%g, %g]\n", f->background(), lo, hi);
        }
        const openvdb::math::Transform& xf = grid->transform();
        const openvdb::Vec3d vs = xf.voxelSize();
        std::printf("  transform %s, voxel size (%g %g %g), index->world matrix (rows):\n",
                    xf.mapType().c_str(), vs.x(), vs.y(), vs.z());
        const openvdb::Mat4d m = xf.baseMap()->getAffineMap()->getMat4();
        // OpenVDB's matrices act on row vectors: world = index * m.
        for (int r = 0; r < 4; ++r) {
            std::printf("    %g %g %g %g\n", m(r, 0), m(r, 1), m(r, 2), m(r, 3));
        }
        for (auto it = grid->beginMeta(); it != grid->endMeta(); ++it) {
            std::printf("  meta %s (%s) = %s\n", it->first.c_str(), it->second->typeName().c_str(),
                        it->second->str().c_str());
        }
    }
    std::printf("total %zu grids, %ju active voxels\n", grids->size(), uintmax_t(total_active));
    return 0;
}

// Value noise on the integer lattice, hashed (no tables, so no seed state): in [0, 1).
float Hash(int x, int y, int z) {
    uint32_t h = uint32_t(x) * 0x8da6b343u ^ uint32_t(y) * 0xd8163841u ^ uint32_t(z) * 0xcb1ab31fu;
    h ^= h >> 13;
    h *= 0x5bd1e995u;
    h ^= h >> 15;
    return float(h & 0xffffffu) / float(0x1000000);
}

float ValueNoise(double x, double y, double z) {
    const int ix = int(std::floor(x)), iy = int(std::floor(y)), iz = int(std::floor(z));
    const auto smooth = [](double t) { return t * t * (3 - 2 * t); };
    const double fx = smooth(x - ix), fy = smooth(y - iy), fz = smooth(z - iz);
    double v = 0;
    for (int c = 0; c < 8; ++c) {
        const int dx = c & 1, dy = (c >> 1) & 1, dz = c >> 2;
        const double w = (dx ? fx : 1 - fx) * (dy ? fy : 1 - fy) * (dz ? fz : 1 - fz);
        v += w * Hash(ix + dx, iy + dy, iz + dz);
    }
    return float(v);
}

// Five octaves, in [0, 1).
float Fractal(double x, double y, double z) {
    double sum = 0, amplitude = 0.5, norm = 0;
    for (int octave = 0; octave < 5; ++octave) {
        sum += amplitude * ValueNoise(x, y, z);
        norm += amplitude;
        x *= 2.03, y *= 2.03, z *= 2.03;
        amplitude *= 0.5;
    }
    return float(sum / norm);
}

int Smoke(const std::string& path, int n) {
    if (n < 8 || n > 1024) {
        std::fprintf(stderr, "media_grid smoke: N=%d: expected 8 to 1024\n", n);
        return 2;
    }
    openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(0.0f);
    grid->setName("density");
    grid->setGridClass(openvdb::GRID_FOG_VOLUME);
    // Index (i, j, k) in [0, n) sits at world (i + 0.5) * 2/n - 1: a 2 m cube about the origin.
    const double voxel = 2.0 / n;
    openvdb::math::Transform::Ptr xf = openvdb::math::Transform::createLinearTransform(voxel);
    xf->postTranslate(openvdb::Vec3d(-1 + voxel / 2));
    grid->setTransform(xf);
    openvdb::FloatGrid::Accessor acc = grid->getAccessor();
    for (int k = 0; k < n; ++k) {
        for (int j = 0; j < n; ++j) {
            for (int i = 0; i < n; ++i) {
                const openvdb::Vec3d p = xf->indexToWorld(openvdb::Coord(i, j, k));
                const double r = p.length();
                if (r >= 0.95) continue;
                // Billows: noise of 4 cells a metre, thresholded, faded towards the sphere.
                const float noise = Fractal(4 * p.x() + 17.3, 4 * p.y() + 5.1, 4 * p.z() + 9.7);
                const float fade = float(1 - r / 0.95);
                const float d = std::fmin(1.0f, 6.0f * (noise - 0.5f) + 1.5f * fade - 0.2f);
                if (d > 0) acc.setValue(openvdb::Coord(i, j, k), d);
            }
        }
    }
    grid->pruneGrid();
    // The density integral along the central column (x = y = 0, through z): times sigma_t at
    // density 1 it is the optical depth through the middle of the smoke.
    double column = 0;
    for (int k = 0; k < n; ++k) column += acc.getValue(openvdb::Coord(n / 2, n / 2, k)) * voxel;
    openvdb::io::File file(path);
    file.setCompression(openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK);
    file.write({grid});
    file.close();
    std::printf(
        "%s: %d^3 smoke, %ju active voxels, %ju bytes, central column density integral %.4g m\n",
        path.c_str(), n, uintmax_t(grid->activeVoxelCount()),
        uintmax_t(std::filesystem::file_size(path)), column);
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    openvdb::initialize();
    const std::string command = argc > 1 ? argv[1] : "";
    try {
        if (command == "info" && argc == 3) return Info(argv[2]);
        if (command == "smoke" && argc == 4) return Smoke(argv[2], std::atoi(argv[3]));
    } catch (const openvdb::Exception& e) {
        std::fprintf(stderr, "media_grid %s: %s\n", command.c_str(), e.what());
        return 1;
    }
    std::fprintf(stderr, "usage: media_grid info FILE.vdb | media_grid smoke OUT.vdb N\n");
    return 2;
}
