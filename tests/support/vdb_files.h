// .vdb files for tests, made in memory with OpenVDB: what grid media read. Tests including this
// link OpenVDB::openvdb (tests/CMakeLists.txt).
#pragma once

#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>

#include <sstream>
#include <string>

namespace lf::testing {

// The grids as the bytes of a .vdb file; `stats` writes the metadata that records each grid's
// bounding box (as OpenVDB's writers do by default).
inline std::string VdbBytes(const openvdb::GridPtrVec& grids, bool stats = true) {
    openvdb::initialize();
    std::ostringstream out(std::ios::binary);
    openvdb::io::Stream stream(out);
    stream.setGridStatsMetadataEnabled(stats);
    stream.write(grids);
    return out.str();
}

// Float grid `name` of `value` at every lattice point of [0, n)^3, voxels `voxel` wide.
inline openvdb::FloatGrid::Ptr ConstantGrid(const std::string& name, float value, int n,
                                            double voxel = 1) {
    openvdb::initialize();
    openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(0);
    grid->setName(name);
    grid->setTransform(openvdb::math::Transform::createLinearTransform(voxel));
    grid->fill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(n - 1)), value, true);
    return grid;
}

}  // namespace lf::testing
