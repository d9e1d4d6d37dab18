// liblf_vdb.so: the part of LoadVolumeGrid that needs OpenVDB (lf/core/vdb_reader.h).
#include "lf/core/vdb_reader.h"

#include <openvdb/io/Stream.h>
#include <openvdb/math/Maps.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Dense.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <exception>
#include <sstream>
#include <type_traits>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "lf/core/volume_grid.h"
#include "lf/version.h"

namespace lf {
namespace {

// Why the box [lo, hi] (inclusive) holds too many lattice points for a dense copy, or "".
// Each side is below 2^33, so the product in double is exact near the bound.
// Lattice coordinates beyond this would overflow the int arithmetic of lookups (VolumeGrid::At
// subtracts the box's corner, the majorant grid rounds up past it).
constexpr int kMaxLatticeCoordinate = 1 << 30;

std::string TooLarge(const openvdb::Coord& lo, const openvdb::Coord& hi) {
    double points = 1;
    for (int a = 0; a < 3; ++a) points *= std::max(0.0, double(hi[a]) - lo[a] + 1);
    if (points == 0) return "";  // an empty box (OpenVDB's is inverted): nothing to copy
    if (points <= double(kMaxVolumeGridPoints)) {
        for (int a = 0; a < 3; ++a) {
            if (std::abs(int64_t(lo[a])) > kMaxLatticeCoordinate ||
                std::abs(int64_t(hi[a])) > kMaxLatticeCoordinate) {
                return absl::StrCat("[", lo[0], ", ", lo[1], ", ", lo[2], "] .. [", hi[0], ", ",
                                    hi[1], ", ", hi[2],
                                    "], beyond the lattice coordinates of +-2^30");
            }
        }
        return "";
    }
    return absl::StrCat(int64_t(hi[0]) - lo[0] + 1, " x ", int64_t(hi[1]) - lo[1] + 1, " x ",
                        int64_t(hi[2]) - lo[2] + 1, " voxels, above the limit of ",
                        kMaxVolumeGridPoints, " (2^28)");
}

// The bounding box the writer recorded (Grid::addStatsMetadata), when it did: TooLarge's
// verdict on it.
std::string RecordedTooLarge(const openvdb::GridBase& grid) {
    const auto lo = grid.getMetadata<openvdb::Vec3IMetadata>(openvdb::GridBase::META_FILE_BBOX_MIN);
    const auto hi = grid.getMetadata<openvdb::Vec3IMetadata>(openvdb::GridBase::META_FILE_BBOX_MAX);
    if (!lo || !hi) return "";
    return TooLarge(openvdb::Coord(lo->value()), openvdb::Coord(hi->value()));
}

// An exception's text for a message: OpenVDB may quote whatever a forged file holds.
std::string Brief(const char* what) {
    std::string text(what);
    constexpr size_t kMaxChars = 200;
    if (text.size() > kMaxChars) text = text.substr(0, kMaxChars) + "...";
    return text;
}

absl::Status Read(const std::string& bytes, const std::string& file_name,
                  const std::string& grid_name, VdbGridRead& out) {
    // Thread-safe once: a static's initialisation.
    [[maybe_unused]] static const bool initialized = (openvdb::initialize(), true);
    const std::string where = absl::StrCat(file_name, " grid \"", grid_name, "\"");
    auto invalid = [&](const std::string& why) {
        return absl::InvalidArgumentError(absl::StrCat(where, ": ", why));
    };
    int32_t magic = 0;
    if (bytes.size() >= sizeof(magic)) std::memcpy(&magic, bytes.data(), sizeof(magic));
    if (magic != openvdb::OPENVDB_MAGIC) {
        return absl::InvalidArgumentError(
            absl::StrCat(file_name, ": not a readable OpenVDB file (no .vdb header)"));
    }
    openvdb::GridBase::Ptr base;
    try {
        std::istringstream in(bytes);
        // OpenVDB does not check every read: past the end of a truncated or forged file it goes
        // on with sizes it never read (a blosc block of ~10^14 bytes, say). A stream that
        // throws at the first short read stops it there. Everything is read now, not delayed:
        // delayed loading reads the values later from a temporary copy of the file, through a
        // stream of its own that does not throw. The tree costs at most a few dozen times the
        // file's bytes (a leaf of 512 values takes at least its 64-byte mask and origin in the
        // file), which the blob limits bound; the dense copy is checked before it is made.
        in.exceptions(std::ios::failbit | std::ios::badbit);
        openvdb::io::Stream stream(in, /*delayLoad=*/false);
        const openvdb::GridPtrVecPtr grids = stream.getGrids();
        std::vector<std::string> names;
        for (const openvdb::GridBase::Ptr& g : *grids) {
            if (g->getName() == grid_name && !base) base = g;
            names.push_back(absl::StrCat("\"", g->getName(), "\" (", g->valueType(), ")"));
        }
        if (!base) {
            return invalid(absl::StrCat("no such grid; the file has ",
                                        names.empty() ? "none" : absl::StrJoin(names, ", ")));
        }
    } catch (const std::exception& e) {
        return absl::InvalidArgumentError(
            absl::StrCat(file_name, ": not a readable OpenVDB file (", Brief(e.what()), ")"));
    }
    const openvdb::FloatGrid::Ptr grid = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
    if (!grid) {
        return invalid(absl::StrCat("a ", base->valueType(), " grid; media read float grids only"));
    }
    if (const std::string why = RecordedTooLarge(*grid); !why.empty()) {
        return invalid("its metadata gives a bounding box of " + why);
    }
    if (!grid->transform().isLinear()) {
        return invalid(absl::StrCat("a ", grid->transform().mapType(),
                                    " transform; media read grids with affine transforms only"));
    }

    VolumeGrid& g = out.grid;
    g.name = absl::StrCat(file_name, "#", grid_name);
    g.background = grid->background();
    if (!(std::isfinite(g.background) && g.background >= 0)) {
        return invalid(absl::StrCat("background ", g.background, ": expected a finite value >= 0"));
    }
    openvdb::Mat4d m;
    try {
        // Made from a scale map's matrix, which OpenVDB refuses when it is nearly singular.
        m = grid->transform().baseMap()->getAffineMap()->getMat4();
    } catch (const std::exception&) {
        return invalid("its transform is singular");
    }
    for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 4; ++c) out.index_to_world[size_t(r)][size_t(c)] = m(r, c);
    }
    // Before the copy, which may be large: LoadVolumeGrid checks the inverse with the medium's
    // transform too.
    if (const double det = m.getMat3().det(); !(std::isfinite(det) && det != 0)) {
        return invalid("its transform is singular");
    }

    try {
        const openvdb::CoordBBox box = grid->evalActiveVoxelBoundingBox();
        if (const std::string why = TooLarge(box.min(), box.max()); !why.empty()) {
            return invalid("its active voxels span a bounding box of " + why);
        }
        // No active voxel: everything reads the background.
        if (box.empty()) return absl::OkStatus();
        for (int a = 0; a < 3; ++a) {
            g.min[size_t(a)] = box.min()[a];
            g.size[size_t(a)] = box.max()[a] - box.min()[a] + 1;
        }
        g.values.resize(size_t(g.size[0]) * size_t(g.size[1]) * size_t(g.size[2]));
        openvdb::tools::Dense<float, openvdb::tools::LayoutXYZ> dense(box, g.values.data());
        openvdb::tools::copyToDense(*grid, dense);
    } catch (const std::exception& e) {
        return invalid(absl::StrCat("its voxels cannot be read (", Brief(e.what()), ")"));
    }
    return absl::OkStatus();
}

}  // namespace
}  // namespace lf

// No exception leaves the module: those OpenVDB throws are caught above, any other here.
extern "C" __attribute__((visibility("default"))) void lf_read_vdb_grid(
    const std::string& bytes, const std::string& file_name, const std::string& grid_name,
    lf::VdbGridRead& out) {
    static_assert(std::is_same_v<decltype(&lf_read_vdb_grid), lf::ReadVdbGridFunction>);
    const std::string failed = absl::StrCat(file_name, ": reading grid \"", grid_name, "\" failed");
    try {
        out.status = lf::Read(bytes, file_name, grid_name, out);
    } catch (const std::exception& e) {
        out.status = absl::InternalError(absl::StrCat(failed, ": ", lf::Brief(e.what())));
    } catch (...) {
        out.status = absl::InternalError(failed);
    }
}

extern "C" __attribute__((visibility("default"))) const char* lf_vdb_build() {
    static_assert(std::is_same_v<decltype(&lf_vdb_build), lf::VdbBuildFunction>);
    static const std::string build = lf::VdbModuleBuild();
    return build.c_str();
}
