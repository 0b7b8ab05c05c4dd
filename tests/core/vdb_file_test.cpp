// VDB files (vdb_file.hpp): a bake's grids are written with Blosc and say so in their metadata;
// the same grids written with Blosc, zlib or no compression read back to the same voxels, bit
// for bit; tiles written with zlib or uncompressed (an older dqjulia's) still merge, into the
// same grids as Blosc tiles.
#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>

#include <openvdb/openvdb.h>

#include "files/atomic_file.hpp"
#include "dqjulia/bake.hpp"
#include "dqjulia/params.hpp"
#include "dqjulia/tiles.hpp"
#include "test_support.hpp"
#include "files/vdb_file.hpp"
#include "bake_fixture.hpp"

namespace fs = std::filesystem;
using namespace dqj;

namespace {

using VdbFiles = dqj::test::BakeFolder;

/// A small bake of the default fractal with a level set, a fog volume and a colour grid (the
/// colour grid is the one class OpenVDB compresses with zlib too).
Params smallBake() {
    Params params;
    params.bake.resolution = 48;
    params.bake.grids = {BakeGrid::Surface, BakeGrid::Density, BakeGrid::Color};
    return params;
}

std::map<std::string, openvdb::GridBase::Ptr> byName(const VdbContents& contents) {
    std::map<std::string, openvdb::GridBase::Ptr> grids;
    for (const openvdb::GridBase::Ptr& grid : *contents.grids) grids[grid->getName()] = grid;
    return grids;
}

bool sameBits(float a, float b) { return std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b); }
bool sameBits(const openvdb::Vec3s& a, const openvdb::Vec3s& b) {
    return sameBits(a.x(), b.x()) && sameBits(a.y(), b.y()) && sameBits(a.z(), b.z());
}

/// Values (bit for bit) and active states that differ between two grids of one type, over
/// every voxel and tile of `a`, and whether their trees have the same topology.
template <typename GridT>
std::uint64_t differences(const GridT& a, const GridT& b) {
    std::uint64_t count = a.tree().hasSameTopology(b.tree()) ? 0 : 1;
    auto other = b.getConstAccessor();
    for (auto value = a.tree().cbeginValueAll(); value; ++value) {
        const openvdb::Coord ijk = value.getCoord();
        if (value.isValueOn() != other.isValueOn(ijk) || !sameBits(*value, other.getValue(ijk))) ++count;
    }
    return count;
}

std::uint64_t differences(const openvdb::GridBase& a, const openvdb::GridBase& b) {
    if (a.type() != b.type()) return 1;
    if (const auto* vectors = dynamic_cast<const openvdb::Vec3SGrid*>(&a))
        return differences(*vectors, static_cast<const openvdb::Vec3SGrid&>(b));
    return differences(static_cast<const openvdb::FloatGrid&>(a), static_cast<const openvdb::FloatGrid&>(b));
}

/// Every grid of `expected` in `actual` under its name, with its class, its voxels and tiles.
void expectSameGrids(const VdbContents& expected, const VdbContents& actual, const std::string& what) {
    auto grids = byName(actual);
    ASSERT_EQ(grids.size(), expected.grids->size()) << what;
    for (const openvdb::GridBase::Ptr& grid : *expected.grids) {
        const openvdb::GridBase::Ptr& other = grids[grid->getName()];
        ASSERT_TRUE(other) << what << ": no grid " << grid->getName();
        EXPECT_EQ(other->getGridClass(), grid->getGridClass()) << what << ", " << grid->getName();
        EXPECT_EQ(other->activeVoxelCount(), grid->activeVoxelCount()) << what << ", " << grid->getName();
        EXPECT_GT(grid->activeVoxelCount(), 1000u) << what << ", " << grid->getName();
        EXPECT_EQ(differences(*grid, *other), 0u) << what << ", " << grid->getName();
    }
}

std::string compressionOf(const openvdb::GridBase& grid) {
    return grid.metaValue<std::string>(openvdb::GridBase::META_FILE_COMPRESSION);
}

void rewrite(const std::string& file, VdbCompression compression) {
    const VdbContents contents = readVdbFile(file);
    AtomicFile out(file);
    writeVdbFile(out, *contents.grids, *contents.metadata, compression);
}

}  // namespace

TEST_F(VdbFiles, ABakeIsWrittenWithBloscAndSaysSo) {
    bakeVdb(smallBake(), path("blosc.vdb"));
    const VdbContents contents = readVdbFile(path("blosc.vdb"));
    ASSERT_EQ(contents.grids->size(), 3u);
    for (const openvdb::GridBase::Ptr& grid : *contents.grids)
        EXPECT_EQ(compressionOf(*grid), "blosc + active values") << grid->getName();
    EXPECT_EQ(vdbCompressionFlags(VdbCompression::Blosc),
              openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK);
    EXPECT_TRUE(openvdb::io::Archive::hasBloscCompression());
}

TEST_F(VdbFiles, EveryCompressionReadsBackToTheSameVoxels) {
    bakeVdb(smallBake(), path("bake.vdb"));
    const VdbContents baked = readVdbFile(path("bake.vdb"));  // the grids as a bake holds them
    // OpenVDB's words for each grid's compression: zlib is never applied to level sets and fog
    // volumes (io::Archive::setGridCompression).
    struct Kind {
        VdbCompression compression;
        const char* name;
        const char* levelSetAndFog;
        const char* color;
    };
    std::map<std::string, std::uintmax_t> sizes;
    for (const Kind& kind : {Kind{VdbCompression::Blosc, "blosc", "blosc + active values", "blosc + active values"},
                             Kind{VdbCompression::Zip, "zip", "active values", "zip + active values"},
                             Kind{VdbCompression::None, "none", "active values", "active values"}}) {
        const std::string file = path(std::string(kind.name) + ".vdb");
        {
            AtomicFile out(file);
            writeVdbFile(out, *baked.grids, *baked.metadata, kind.compression);
        }
        sizes[kind.name] = fs::file_size(file);
        const VdbContents read = readVdbFile(file);
        expectSameGrids(baked, read, kind.name);
        for (const openvdb::GridBase::Ptr& grid : *read.grids)
            EXPECT_EQ(compressionOf(*grid), grid->getName() == "color" ? kind.color : kind.levelSetAndFog)
                << kind.name << ", " << grid->getName();
        EXPECT_EQ(read.metadata->metaValue<std::string>("dqjulia_parameters"),
                  baked.metadata->metaValue<std::string>("dqjulia_parameters"));
    }
    // Both compress (Blosc the level set and the fog volume too, which zlib leaves alone, but
    // LZ4 less than deflate: the colour grid is the larger share here, and zlib's file the
    // smaller); the bake's own file is the Blosc one.
    EXPECT_EQ(sizes["blosc"], fs::file_size(path("bake.vdb")));
    EXPECT_LT(sizes["blosc"], sizes["none"] * 9 / 10);
    EXPECT_LT(sizes["zip"], sizes["none"] * 9 / 10);
    std::printf("[ figures  ] 48^3 surface, density, color: blosc %ju bytes, zip %ju, none %ju\n", sizes["blosc"],
                sizes["zip"], sizes["none"]);
}

TEST_F(VdbFiles, ZipAndUncompressedTilesStillMerge) {
    Params params = smallBake();
    Tile tile = parseTiling("3x1x1");
    std::vector<std::string> tiles;
    for (tile.index = 1; tile.index <= tileCount(tile); ++tile.index) {
        BakeOptions options;
        options.tile = tile;
        tiles.push_back(tilePath(path("whole.vdb"), tile.index));
        bakeVdb(params, tiles.back(), options);
    }
    mergeTiles(tiles, path("blosc.vdb"));
    // Tiles as an older dqjulia wrote them: zlib (its OpenVDB had no Blosc) and uncompressed.
    rewrite(tiles[0], VdbCompression::Zip);
    rewrite(tiles[1], VdbCompression::None);
    EXPECT_EQ(compressionOf(*findGrid(readVdbFile(tiles[0]), "color")), "zip + active values");
    mergeTiles(tiles, path("mixed.vdb"));
    const VdbContents mixed = readVdbFile(path("mixed.vdb"));
    expectSameGrids(readVdbFile(path("blosc.vdb")), mixed, "merged from zip, none and blosc tiles");
    for (const openvdb::GridBase::Ptr& grid : *mixed.grids)
        EXPECT_EQ(compressionOf(*grid), "blosc + active values") << grid->getName();
}

// OpenVDB reads bools straight from a file's bytes; a byte other than 0 or 1 must read as true
// (a bool holding 7 is undefined behaviour, and may compare unequal to true). The file
// (tests/robustness/make_vdb_seeds.py) holds a bool grid's root tile stored as value 7,
// active 9, and the file metadata `flagged` stored as 2.
TEST_F(VdbFiles, BoolsStoredAsOtherBytesReadAsTrue) {
    const VdbContents contents = readVdbFile(std::string(DQJ_VDB_CORPUS) + "/bool-bytes.vdb");
    const auto flags = openvdb::gridPtrCast<openvdb::BoolGrid>(findGrid(contents, "flags"));
    ASSERT_TRUE(flags);
    bool value = false;
    EXPECT_TRUE(flags->tree().probeValue(openvdb::Coord(12288 + 100, 20480, 28672 + 4095), value));  // active
    EXPECT_EQ(value, true);
    EXPECT_EQ(flags->tree().activeTileCount(), 1u);
    EXPECT_EQ(contents.metadata->metaValue<bool>("flagged"), true);
    const auto density = openvdb::gridPtrCast<openvdb::FloatGrid>(findGrid(contents, "density"));
    ASSERT_TRUE(density);
    EXPECT_EQ(density->activeVoxelCount(), 16u * 16u * 16u);
}
