#include "lf/core/volume_grid.h"

#include <gtest/gtest.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>

#include <cmath>
#include <limits>
#include <string>

#include "vdb_files.h"

namespace lf {
namespace {

class VolumeGridTest : public ::testing::Test {
  protected:
    static void SetUpTestSuite() { openvdb::initialize(); }

    // A 4 x 3 x 2 block of distinct values from (-1, 2, 5), voxels 0.5 wide, moved by (1, 2, 3).
    static openvdb::FloatGrid::Ptr Block(const std::string& name = "density") {
        openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(0.25f);
        grid->setName(name);
        openvdb::math::Transform::Ptr transform =
            openvdb::math::Transform::createLinearTransform(0.5);
        transform->postTranslate(openvdb::Vec3d(1, 2, 3));
        grid->setTransform(transform);
        openvdb::FloatGrid::Accessor acc = grid->getAccessor();
        for (int z = 0; z < 2; ++z) {
            for (int y = 0; y < 3; ++y) {
                for (int x = 0; x < 4; ++x) {
                    acc.setValue(openvdb::Coord(x - 1, y + 2, z + 5),
                                 float(1 + x + 4 * y + 12 * z));
                }
            }
        }
        return grid;
    }

    static absl::StatusOr<std::shared_ptr<const VolumeGrid>> Load(
        const std::string& bytes, const std::string& grid = "density",
        const Affine& transform = Affine()) {
        return LoadVolumeGrid(bytes, "smoke.vdb", grid, transform);
    }

    static void ExpectError(const absl::StatusOr<std::shared_ptr<const VolumeGrid>>& grid,
                            const std::string& expected) {
        ASSERT_FALSE(grid.ok()) << "expected an error containing: " << expected;
        EXPECT_EQ(grid.status().code(), absl::StatusCode::kInvalidArgument);
        EXPECT_NE(grid.status().message().find(expected), std::string::npos)
            << grid.status().message() << "\nexpected: " << expected;
    }
};

TEST_F(VolumeGridTest, CopiesTheActiveBoxAndTheBackground) {
    const openvdb::FloatGrid::Ptr block = Block();
    absl::StatusOr<std::shared_ptr<const VolumeGrid>> grid = Load(testing::VdbBytes({block}));
    ASSERT_TRUE(grid.ok()) << grid.status();
    const VolumeGrid& g = **grid;
    EXPECT_EQ(g.name, "smoke.vdb#density");
    EXPECT_EQ(g.min, (std::array<int, 3>{-1, 2, 5}));
    EXPECT_EQ(g.size, (std::array<int, 3>{4, 3, 2}));
    EXPECT_EQ(g.values.size(), 24u);
    EXPECT_EQ(g.background, 0.25f);
    const openvdb::FloatGrid::ConstAccessor acc = block->getConstAccessor();
    for (int z = 3; z < 9; ++z) {
        for (int y = 0; y < 7; ++y) {
            for (int x = -3; x < 5; ++x) {
                EXPECT_EQ(g.At(x, y, z), acc.getValue(openvdb::Coord(x, y, z)))
                    << x << " " << y << " " << z;
            }
        }
    }
    // x fastest.
    EXPECT_EQ(g.values[1], 2.0f);
    EXPECT_EQ(g.values[4], 5.0f);
    EXPECT_EQ(g.values[12], 13.0f);
}

// Lookup is OpenVDB's BoxSampler: the values at lattice points, trilinear between them, and
// the background beyond the box.
TEST_F(VolumeGridTest, LookupMatchesOpenVdbsBoxSampler) {
    const openvdb::FloatGrid::Ptr block = Block();
    absl::StatusOr<std::shared_ptr<const VolumeGrid>> grid = Load(testing::VdbBytes({block}));
    ASSERT_TRUE(grid.ok()) << grid.status();
    const openvdb::FloatGrid::ConstAccessor acc = block->getConstAccessor();
    int between = 0;
    for (double z = 3.5; z < 8; z += 0.3) {
        for (double y = 0.25; y < 6; y += 0.35) {
            for (double x = -2.75; x < 4; x += 0.45) {
                const float expected =
                    openvdb::tools::BoxSampler::sample(acc, openvdb::Vec3R(x, y, z));
                EXPECT_NEAR((*grid)->Lookup(Vec3d(x, y, z)), expected, 1e-5)
                    << x << " " << y << " " << z;
                between += x != std::floor(x);
            }
        }
    }
    EXPECT_GT(between, 100);
    EXPECT_EQ((*grid)->Lookup(Vec3d(0, 3, 5)), 6.0f);  // a voxel centre
    EXPECT_EQ((*grid)->Lookup(Vec3d(1e6, -4e7, 0.5)), 0.25f);
}

// index_to_world is the file's transform, then the medium's; world_to_index its inverse.
TEST_F(VolumeGridTest, TransformIsTheFilesThenTheMediums) {
    const openvdb::FloatGrid::Ptr block = Block();
    Affine medium;
    medium.m = {{{0, -2, 0, 10}, {2, 0, 0, 0}, {0, 0, 2, -1}}};
    absl::StatusOr<std::shared_ptr<const VolumeGrid>> grid =
        Load(testing::VdbBytes({block}), "density", medium);
    ASSERT_TRUE(grid.ok()) << grid.status();
    for (const Vec3d& ijk : {Vec3d(0, 0, 0), Vec3d(-1, 2, 5), Vec3d(3.5, -1, 7.25)}) {
        const openvdb::Vec3d file = block->indexToWorld(openvdb::Vec3d(ijk.x, ijk.y, ijk.z));
        const Vec3d expected = medium.Apply(Vec3d(file.x(), file.y(), file.z()));
        const Vec3d world = (*grid)->index_to_world.Apply(ijk);
        const Vec3d back = (*grid)->world_to_index.Apply(world);
        for (int a = 0; a < 3; ++a) {
            EXPECT_NEAR(world[a], expected[a], 1e-12);
            EXPECT_NEAR(back[a], ijk[a], 1e-12);
        }
    }
}

TEST_F(VolumeGridTest, EmptyGridIsAllBackground) {
    openvdb::FloatGrid::Ptr empty = openvdb::FloatGrid::create(0.5f);
    empty->setName("density");
    absl::StatusOr<std::shared_ptr<const VolumeGrid>> grid = Load(testing::VdbBytes({empty}));
    ASSERT_TRUE(grid.ok()) << grid.status();
    EXPECT_TRUE((*grid)->values.empty());
    EXPECT_EQ((*grid)->Lookup(Vec3d(0.5, 0.5, 0.5)), 0.5f);
}

TEST_F(VolumeGridTest, MissingGridListsTheFilesGrids) {
    openvdb::Vec3SGrid::Ptr velocity = openvdb::Vec3SGrid::create();
    velocity->setName("velocity");
    ExpectError(Load(testing::VdbBytes({Block("flame"), velocity})),
                "smoke.vdb grid \"density\": no such grid; the file has \"flame\" (float), "
                "\"velocity\" (vec3s)");
}

TEST_F(VolumeGridTest, NonFloatGridIsRefusedByName) {
    openvdb::Vec3SGrid::Ptr velocity = openvdb::Vec3SGrid::create();
    velocity->setName("velocity");
    ExpectError(Load(testing::VdbBytes({velocity}), "velocity"),
                "smoke.vdb grid \"velocity\": a vec3s grid; media read float grids only");
}

// Two voxels far apart: a bounding box of 1001^3 lattice points, refused from the recorded
// metadata or, without it, from the topology, before the dense copy is allocated.
TEST_F(VolumeGridTest, AbsurdBoundingBoxIsRefusedBeforeTheCopy) {
    openvdb::FloatGrid::Ptr sparse = openvdb::FloatGrid::create(0);
    sparse->setName("density");
    sparse->tree().setValue(openvdb::Coord(0, 0, 0), 1);
    sparse->tree().setValue(openvdb::Coord(1000, 1000, 1000), 1);
    ExpectError(Load(testing::VdbBytes({sparse})),
                "its metadata gives a bounding box of 1001 x 1001 x 1001 voxels, above the limit "
                "of 268435456 (2^28)");
    ExpectError(Load(testing::VdbBytes({sparse}, /*stats=*/false)),
                "its active voxels span a bounding box of 1001 x 1001 x 1001 voxels, above the "
                "limit");
    // Sides whose product overflows 64 bits, and a box one plane beyond 2^10 x 2^10 x 2^8.
    openvdb::FloatGrid::Ptr vast = openvdb::FloatGrid::create(0);
    vast->setName("density");
    vast->tree().setValue(openvdb::Coord(-2000000000, -2000000000, -2000000000), 1);
    vast->tree().setValue(openvdb::Coord(2000000000, 2000000000, 2000000000), 1);
    ExpectError(Load(testing::VdbBytes({vast}, false)),
                "span a bounding box of 4000000001 x 4000000001 x 4000000001 voxels");
    // A small box far out: its coordinates would overflow the lookups' int arithmetic.
    openvdb::FloatGrid::Ptr far = openvdb::FloatGrid::create(0);
    far->setName("density");
    far->tree().setValue(openvdb::Coord(2147483000, 0, 0), 1);
    far->tree().setValue(openvdb::Coord(2147483010, 5, 5), 1);
    ExpectError(Load(testing::VdbBytes({far}, false)),
                "beyond the lattice coordinates of +-2^30");
    openvdb::FloatGrid::Ptr edge = openvdb::FloatGrid::create(0);
    edge->setName("density");
    edge->tree().setValue(openvdb::Coord(0, 0, 0), 1);
    edge->tree().setValue(openvdb::Coord(1023, 1023, 256), 1);
    ExpectError(Load(testing::VdbBytes({edge})), "1024 x 1024 x 257 voxels, above the limit");
}

TEST_F(VolumeGridTest, NegativeOrNonFiniteValuesAreRefused) {
    for (const float bad :
         {-0.5f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
        openvdb::FloatGrid::Ptr grid = Block();
        grid->tree().setValue(openvdb::Coord(1, 3, 6), bad);
        ExpectError(Load(testing::VdbBytes({grid})), "smoke.vdb grid \"density\": value ");
        ExpectError(Load(testing::VdbBytes({grid})),
                    " at voxel (1, 3, 6): expected a finite value >= 0");
    }
    ExpectError(Load(testing::VdbBytes({openvdb::FloatGrid::create(-1)->copyGrid()}), ""),
                "background -1: expected a finite value >= 0");
}

TEST_F(VolumeGridTest, FrustumTransformIsRefused) {
    openvdb::FloatGrid::Ptr grid = Block();
    grid->setTransform(openvdb::math::Transform::createFrustumTransform(
        openvdb::BBoxd(openvdb::Vec3d(0, 0, 0), openvdb::Vec3d(10, 10, 10)), 0.5, 2, 1));
    ExpectError(Load(testing::VdbBytes({grid})),
                "transform; media read grids with affine transforms only");
}

TEST_F(VolumeGridTest, GarbageAndTruncatedBytesAreClearErrors) {
    ExpectError(Load("not a vdb file at all"), "smoke.vdb: not a readable OpenVDB file");
    ExpectError(Load(""), "smoke.vdb: not a readable OpenVDB file");
    const std::string bytes = testing::VdbBytes({Block()});
    for (const size_t length : {size_t(8), bytes.size() / 2, bytes.size() * 3 / 4}) {
        absl::StatusOr<std::shared_ptr<const VolumeGrid>> grid = Load(bytes.substr(0, length));
        ASSERT_FALSE(grid.ok()) << length;
        EXPECT_EQ(grid.status().code(), absl::StatusCode::kInvalidArgument);
        EXPECT_NE(grid.status().message().find("smoke.vdb"), std::string::npos)
            << grid.status().message();
    }
}

}  // namespace
}  // namespace lf
