// The narrow-band signed distance to the mesh of f = 0 (mesh_distance.hpp).
#include "bake/mesh_distance.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <stdexcept>
#include <utility>
#include <vector>

#include <openvdb/tools/Prune.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "bake/sparse_sampler.hpp"
#include "platform/platform.hpp"
#include "platform/thread_scratch.hpp"

namespace dqj {
namespace {

using openvdb::Coord;
using openvdb::Vec3d;
using FloatLeaf = openvdb::FloatTree::LeafNodeType;
constexpr int kDim = int(FloatLeaf::DIM);
const std::uint32_t kNoVertex = openvdb::util::INVALID_IDX;

struct Triangle {
    Vec3d a, b, c;
};

Vec3d closestPointOnSegment(const Vec3d& p, const Vec3d& a, const Vec3d& b) {
    const Vec3d ab = b - a;
    const double length = ab.dot(ab);
    if (length <= 0.0) return a;
    return a + ab * std::clamp((p - a).dot(ab) / length, 0.0, 1.0);
}

/// The point of triangle `t` nearest to `p`: by the region of the triangle's plane `p` projects
/// into (a vertex's, an edge's or the face's), from the dot products of the edges with the
/// vectors to `p`. Degenerate triangles are their longest edge.
Vec3d closestPointOnTriangle(const Vec3d& p, const Triangle& t) {
    const Vec3d ab = t.b - t.a, ac = t.c - t.a;
    if (ab.cross(ac).lengthSqr() <= 1e-24) {
        const Vec3d onAb = closestPointOnSegment(p, t.a, t.b), onAc = closestPointOnSegment(p, t.a, t.c),
                    onBc = closestPointOnSegment(p, t.b, t.c);
        const double dAb = (p - onAb).lengthSqr(), dAc = (p - onAc).lengthSqr(), dBc = (p - onBc).lengthSqr();
        return dAb <= dAc && dAb <= dBc ? onAb : (dAc <= dBc ? onAc : onBc);
    }
    const Vec3d ap = p - t.a;
    const double d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0.0 && d2 <= 0.0) return t.a;
    const Vec3d bp = p - t.b;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0.0 && d4 <= d3) return t.b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return t.a + ab * (d1 / (d1 - d3));
    const Vec3d cp = p - t.c;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0.0 && d5 <= d6) return t.c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return t.a + ac * (d2 / (d2 - d6));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) return t.b + (t.c - t.b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    const double scale = 1.0 / (va + vb + vc);
    return t.a + ab * (vb * scale) + ac * (vc * scale);
}

/// f's mesh in index space: quads and triangles (the fourth index kNoVertex).
struct Mesh {
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec4I> prims;

    int triangleCount(std::size_t prim) const { return prims[prim][3] == kNoVertex ? 1 : 2; }
    /// A quad's two halves share the diagonal from its first to its third vertex, and its turn.
    Triangle triangle(std::size_t prim, int half) const {
        const openvdb::Vec4I& v = prims[prim];
        if (half == 0) return {Vec3d(points[v[0]]), Vec3d(points[v[1]]), Vec3d(points[v[2]])};
        return {Vec3d(points[v[0]]), Vec3d(points[v[2]]), Vec3d(points[v[3]])};
    }
};

Mesh meshOf(const openvdb::FloatGrid& f) {
    openvdb::tools::VolumeToMesh mesher(0.0);
    mesher(f);
    // The mesher's own trees were freed as it returned; handed back before the copies below
    // (at 2048^3 the copies came on top of them: 1.96 GB, the bake's peak; now 1.3 GB).
    platform::releaseFreedMemory();
    Mesh mesh;
    mesh.points.resize(mesher.pointListSize());
    const openvdb::math::Transform& transform = f.transform();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.points.size()),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          for (std::size_t k = range.begin(); k != range.end(); ++k)
                              mesh.points[k] = openvdb::Vec3s(transform.worldToIndex(mesher.pointList()[k]));
                      });
    mesher.pointList().reset(nullptr);
    openvdb::tools::PolygonPoolList& pools = mesher.polygonPoolList();
    std::size_t count = 0;
    for (std::size_t n = 0; n < mesher.polygonPoolListSize(); ++n)
        count += pools[n].numQuads() + pools[n].numTriangles();
    mesh.prims.reserve(count);
    for (std::size_t n = 0; n < mesher.polygonPoolListSize(); ++n) {
        openvdb::tools::PolygonPool& pool = pools[n];
        for (std::size_t q = 0; q < pool.numQuads(); ++q) mesh.prims.push_back(pool.quad(q));
        for (std::size_t t = 0; t < pool.numTriangles(); ++t) {
            const openvdb::Vec3I& v = pool.triangle(t);
            mesh.prims.emplace_back(v[0], v[1], v[2], kNoVertex);
        }
        pool.clearQuads();  // freed once copied
        pool.clearTriangles();
    }
    return mesh;
}

/// A leaf's key: its origin over the leaf's side, each coordinate offset to be positive, in 21
/// bits (so sorting by key sorts by x, then y, then z).
constexpr std::int64_t kKeyOffset = std::int64_t(1) << 20;
std::uint64_t leafKey(const Coord& voxel) {
    auto part = [](int v) {
        const std::int64_t leaf = (std::int64_t(v) >> 3) + kKeyOffset;
        if (leaf < 0 || leaf >= 2 * kKeyOffset) throw std::length_error("levelSetOfMesh: the grid is too large");
        return std::uint64_t(leaf);
    };
    return (part(voxel.x()) << 42) | (part(voxel.y()) << 21) | part(voxel.z());
}
Coord leafOrigin(std::uint64_t key) {
    auto part = [](std::uint64_t bits) { return int((std::int64_t(bits & 0x1FFFFF) - kKeyOffset) * kDim); };
    return {part(key >> 42), part(key >> 21), part(key)};
}

/// The bit of a leaf's neighbour (each of dx, dy, dz in -1..1) in a 27-bit set of leaves.
constexpr std::uint32_t neighbourBit(int dx, int dy, int dz) { return 1u << ((dx + 1) * 9 + (dy + 1) * 3 + dz + 1); }

/// The primitives of each leaf ("home": its first vertex's leaf), sorted by the leaf's key, and
/// which of the home's neighbour leaves each one's box grown by a voxel reaches. Quads span at
/// most 2 x 2 x 1 cells, so they reach only their home's neighbours; the rare primitive that
/// reaches farther is "large" and tested by every leaf.
struct Homes {
    std::vector<std::uint64_t> keys;  // the leaves that are homes, sorted
    std::vector<std::size_t> start;   // prims of keys[k]: order[start[k]] .. order[start[k + 1]]
    std::vector<std::uint32_t> order;
    std::vector<std::uint32_t> reaches;  // order[i]'s neighbour leaves (neighbourBit)
    std::vector<std::uint32_t> large;

    Homes(const Mesh& mesh) {
        if (mesh.prims.size() >= std::size_t(std::numeric_limits<std::uint32_t>::max()))
            throw std::length_error("levelSetOfMesh: too many polygons");
        std::vector<std::pair<std::uint64_t, std::uint32_t>> byKey(mesh.prims.size());
        std::vector<std::uint32_t> reach(mesh.prims.size(), 0);  // 0: large
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.prims.size()),
                          [&](const tbb::blocked_range<std::size_t>& range) {
                              for (std::size_t prim = range.begin(); prim != range.end(); ++prim) {
                                  const openvdb::Vec4I& v = mesh.prims[prim];
                                  openvdb::Vec3s low = mesh.points[v[0]], high = low;
                                  for (int k = 1; k < 4 && v[k] != kNoVertex; ++k) {
                                      low = openvdb::math::minComponent(low, mesh.points[v[k]]);
                                      high = openvdb::math::maxComponent(high, mesh.points[v[k]]);
                                  }
                                  const Coord home = Coord::floor(mesh.points[v[0]]);
                                  Coord from, to;
                                  bool local = true;
                                  for (int axis = 0; axis < 3; ++axis) {
                                      const int origin = home[axis] & ~(kDim - 1);
                                      from[axis] = (int(std::ceil(low[axis] - 1.0f)) - origin) >> 3;
                                      to[axis] = (int(std::floor(high[axis] + 1.0f)) - origin) >> 3;
                                      local = local && from[axis] >= -1 && to[axis] <= 1;
                                  }
                                  std::uint32_t bits = 0;
                                  for (int dx = from.x(); local && dx <= to.x(); ++dx)
                                      for (int dy = from.y(); dy <= to.y(); ++dy)
                                          for (int dz = from.z(); dz <= to.z(); ++dz) bits |= neighbourBit(dx, dy, dz);
                                  reach[prim] = bits;
                                  byKey[prim] = {leafKey(home), std::uint32_t(prim)};
                              }
                          });
        tbb::parallel_sort(byKey.begin(), byKey.end());
        order.reserve(byKey.size());
        for (const auto& [key, prim] : byKey) {
            if (reach[prim] == 0) {
                large.push_back(prim);
                continue;
            }
            if (keys.empty() || keys.back() != key) {
                keys.push_back(key);
                start.push_back(order.size());
            }
            order.push_back(prim);
            reaches.push_back(reach[prim]);
        }
        start.push_back(order.size());
        std::sort(large.begin(), large.end());
    }

    /// Calls `visit(prim)` for each primitive homed in the leaf of `key` that reaches the
    /// home's neighbour `bit`.
    template <typename Visit>
    void forEachIn(std::uint64_t key, std::uint32_t bit, Visit&& visit) const {
        const auto at = std::lower_bound(keys.begin(), keys.end(), key);
        if (at == keys.end() || *at != key) return;
        const std::size_t k = std::size_t(at - keys.begin());
        for (std::size_t i = start[k]; i != start[k + 1]; ++i)
            if (reaches[i] & bit) visit(order[i]);
    }
};

/// The near voxels of one leaf: within a voxel of the mesh, their signed distance and nearest point.
struct NearLeaf {
    std::vector<std::uint16_t> offsets;    // in the leaf
    std::vector<float> distances;          // signed, voxels
    std::vector<openvdb::Vec3f> points;    // the nearest points
    std::vector<std::uint32_t> triangles;  // theirs: prim * 2 + half
    bool empty() const { return offsets.empty(); }
};

/// Two distances (squared) this close are the same point of the mesh reached from two triangles.
constexpr double kTie = 1e-9;

NearLeaf nearVoxels(const Mesh& mesh, const Homes& homes, std::uint64_t key,
                    openvdb::tree::ValueAccessor<const openvdb::BoolTree>& inside) {
    const Coord origin = leafOrigin(key);
    std::array<double, FloatLeaf::SIZE> best;
    std::array<double, FloatLeaf::SIZE> facing{};  // the nearest triangles' normal against the way to the voxel
    std::array<Vec3d, FloatLeaf::SIZE> nearest;
    std::array<std::uint32_t, FloatLeaf::SIZE> nearestTriangle;
    best.fill(std::numeric_limits<double>::infinity());
    auto testTriangle = [&](const Triangle& t, std::uint32_t id) {
        const Vec3d low = openvdb::math::minComponent(t.a, openvdb::math::minComponent(t.b, t.c));
        const Vec3d high = openvdb::math::maxComponent(t.a, openvdb::math::maxComponent(t.b, t.c));
        Coord from, to;
        for (int axis = 0; axis < 3; ++axis) {
            from[axis] = std::max(int(std::ceil(low[axis] - 1.0)), origin[axis]);
            to[axis] = std::min(int(std::floor(high[axis] + 1.0)), origin[axis] + kDim - 1);
            if (from[axis] > to[axis]) return;
        }
        Vec3d normal = (t.b - t.a).cross(t.c - t.a);
        const double area = normal.length();
        normal = area > 0.0 ? normal / area : Vec3d(0.0);
        for (int x = from.x(); x <= to.x(); ++x)
            for (int y = from.y(); y <= to.y(); ++y)
                for (int z = from.z(); z <= to.z(); ++z) {
                    const Vec3d voxel(x, y, z);
                    // Farther than a voxel from the triangle's plane: farther from the triangle.
                    if (area > 0.0 && std::abs(normal.dot(voxel - t.a)) > 1.0) continue;
                    const Vec3d point = closestPointOnTriangle(voxel, t);
                    const Vec3d away = voxel - point;
                    const double squared = away.lengthSqr();
                    if (squared > 1.0) continue;
                    const double cosine = squared > 1e-20 ? normal.dot(away) / std::sqrt(squared) : 0.0;
                    const auto offset =
                        std::size_t(((x - origin.x()) << 6) | ((y - origin.y()) << 3) | (z - origin.z()));
                    if (squared < best[offset] - kTie) {
                        best[offset] = squared;
                        facing[offset] = cosine;
                        nearest[offset] = point;
                        nearestTriangle[offset] = id;
                    } else if (squared <= best[offset] + kTie && std::abs(cosine) > std::abs(facing[offset])) {
                        facing[offset] = cosine;
                    }
                }
    };
    auto test = [&](std::uint32_t prim) {
        for (int half = 0; half < mesh.triangleCount(prim); ++half)
            testTriangle(mesh.triangle(prim, half), prim * 2 + std::uint32_t(half));
    };
    for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz)
                homes.forEachIn(leafKey(origin.offsetBy(dx * kDim, dy * kDim, dz * kDim)), neighbourBit(-dx, -dy, -dz),
                                test);
    for (std::uint32_t prim : homes.large) test(prim);

    NearLeaf result;
    for (std::size_t offset = 0; offset < FloatLeaf::SIZE; ++offset) {
        if (!(best[offset] <= 1.0)) continue;
        const Coord voxel = FloatLeaf::offsetToLocalCoord(openvdb::Index(offset)) + origin;
        // volumeToMesh's faces turn their front (b - a) x (c - a) outwards, to f > 0.
        const bool in = facing[offset] != 0.0 ? facing[offset] < 0.0 : inside.getValue(voxel);
        const double distance = std::sqrt(best[offset]);
        result.offsets.push_back(std::uint16_t(offset));
        result.distances.push_back(float(in ? -distance : distance));
        result.points.emplace_back(nearest[offset]);
        result.triangles.push_back(nearestTriangle[offset]);
    }
    return result;
}

/// The distance to the mesh of a leaf's voxels farther than a voxel from it: to the triangle of
/// the nearest seed (a near voxel's nearest point), the seeds taken from a block around the leaf
/// grown by the band's reach: the nearest in each row along x, then of those along y, then z (a
/// separable vector distance transform: each pass exact for its axis, the three together within
/// a small fraction of a voxel of the nearest seed; the seed's triangle then at most as far).
struct BandBlock {
    int leaves = 0;  // the block reaches this many leaves beyond its own
    int pad = 0;     // voxels
    int side = 0;
    std::vector<std::int32_t> cells[2];
    std::vector<openvdb::Vec3f> points;  // the seeds in the block
    std::vector<std::uint32_t> triangles;

    void reach(int voxels) {
        leaves = (voxels + kDim - 1) / kDim;
        pad = leaves * kDim;
        side = kDim + 2 * pad;
        for (std::vector<std::int32_t>& c : cells) c.resize(std::size_t(side) * std::size_t(side) * std::size_t(side));
    }
    std::size_t at(int x, int y, int z) const {
        const auto n = std::size_t(side);
        return (std::size_t(x) * n + std::size_t(y)) * n + std::size_t(z);
    }
};

/// Not a near voxel.
constexpr float kFar = std::numeric_limits<float>::infinity();

template <typename NearLookup>
std::unique_ptr<FloatLeaf> bandLeaf(BandBlock& block, const Coord& origin, int reach, float band, float voxelSize,
                                    const Mesh& mesh, const NearLookup& nearLeaf,
                                    openvdb::tree::ValueAccessor<const openvdb::BoolTree>& inside) {
    if (block.side == 0) block.reach(reach);
    const int pad = block.pad, around = block.leaves;
    const int low = pad - reach, high = pad + kDim + reach;  // the block's cells in use: [low, high)
    std::vector<std::int32_t>& seeds = block.cells[0];
    std::vector<std::int32_t>& rows = block.cells[1];
    for (int x = low; x < high; ++x)
        for (int y = low; y < high; ++y)
            for (int z = low; z < high; ++z) seeds[block.at(x, y, z)] = -1;
    block.points.clear();
    block.triangles.clear();
    const NearLeaf* own = nullptr;
    for (int dx = -around; dx <= around; ++dx)
        for (int dy = -around; dy <= around; ++dy)
            for (int dz = -around; dz <= around; ++dz) {
                const NearLeaf* leaf = nearLeaf(leafKey(origin.offsetBy(dx * kDim, dy * kDim, dz * kDim)));
                if (!leaf) continue;
                if (dx == 0 && dy == 0 && dz == 0) own = leaf;
                const Coord corner = Coord(dx * kDim, dy * kDim, dz * kDim) + Coord(pad);
                for (std::size_t n = 0; n < leaf->offsets.size(); ++n) {
                    const Coord cell = FloatLeaf::offsetToLocalCoord(leaf->offsets[n]) + corner;
                    if (cell.x() < low || cell.y() < low || cell.z() < low || cell.x() >= high || cell.y() >= high ||
                        cell.z() >= high)
                        continue;
                    seeds[block.at(cell.x(), cell.y(), cell.z())] = std::int32_t(block.points.size());
                    block.points.push_back(leaf->points[n]);
                    block.triangles.push_back(leaf->triangles[n]);
                }
            }
    if (block.points.empty()) return nullptr;
    std::array<float, FloatLeaf::SIZE> nearHere;
    nearHere.fill(kFar);
    if (own)
        for (std::size_t n = 0; n < own->offsets.size(); ++n) nearHere[own->offsets[n]] = own->distances[n];
    const openvdb::Vec3f base = (origin - Coord(pad)).asVec3s();
    // One pass: each cell of [from, to) takes the nearest to it of the seeds `reach` cells
    // either side of it along `axis` in `in`.
    // Lines without a seed (most, where the surface runs along them) are skipped.
    auto pass = [&](const std::vector<std::int32_t>& in, std::vector<std::int32_t>& result, int axis, const Coord& from,
                    const Coord& to) {
        const int across = (axis + 1) % 3, along = (axis + 2) % 3;
        const std::size_t stride =
            axis == 0 ? std::size_t(block.side) * std::size_t(block.side) : (axis == 1 ? std::size_t(block.side) : 1);
        const int cells = to[axis] - from[axis], length = cells + 2 * reach;
        for (int u = from[across]; u < to[across]; ++u)
            for (int w = from[along]; w < to[along]; ++w) {
                Coord cell;
                cell[across] = u;
                cell[along] = w;
                cell[axis] = from[axis] - reach;
                const std::size_t first = block.at(cell.x(), cell.y(), cell.z());
                bool any = false;
                for (int k = 0; k < length && !any; ++k) any = in[first + std::size_t(k) * stride] >= 0;
                for (int c = 0; c < cells; ++c) {
                    std::int32_t best = -1;
                    if (any) {
                        cell[axis] = from[axis] + c;
                        const openvdb::Vec3f centre = base + cell.asVec3s();
                        float nearest = std::numeric_limits<float>::infinity();
                        for (int k = c; k <= c + 2 * reach; ++k) {
                            const std::int32_t seed = in[first + std::size_t(k) * stride];
                            if (seed < 0) continue;
                            const float squared = (block.points[std::size_t(seed)] - centre).lengthSqr();
                            if (squared < nearest) {
                                nearest = squared;
                                best = seed;
                            }
                        }
                    }
                    result[first + std::size_t(c + reach) * stride] = best;
                }
            }
    };
    const Coord inner(pad), outer(pad + kDim);
    pass(seeds, rows, 0, Coord(inner.x(), low, low), Coord(outer.x(), high, high));
    pass(rows, seeds, 1, Coord(inner.x(), inner.y(), low), Coord(outer.x(), outer.y(), high));
    pass(seeds, rows, 2, inner, outer);

    auto leaf = std::make_unique<FloatLeaf>(origin, band * voxelSize, false);
    bool active = false;
    for (openvdb::Index offset = 0; offset < FloatLeaf::SIZE; ++offset) {
        const Coord local = FloatLeaf::offsetToLocalCoord(offset);
        float distance = band;
        if (nearHere[offset] != kFar) {
            distance = nearHere[offset];
        } else {
            const std::int32_t seed = rows[block.at(local.x() + pad, local.y() + pad, local.z() + pad)];
            if (seed >= 0) {
                const std::uint32_t triangle = block.triangles[std::size_t(seed)];
                const Vec3d voxel = (origin + local).asVec3d();
                distance = float(
                    (voxel - closestPointOnTriangle(voxel, mesh.triangle(triangle / 2, int(triangle % 2)))).length());
            }
            if (inside.getValue(origin + local)) distance = -distance;
        }
        // Every voxel's sign is set here (signedFloodFill would give the inactive ones the sign
        // of the active voxel before them in the leaf, wrong beside the band's gaps).
        const bool inBand = std::abs(distance) < band;
        leaf->setValueOnly(offset, inBand ? distance * voxelSize : std::copysign(band * voxelSize, distance));
        if (inBand) {
            leaf->setValueOn(offset);
            active = true;
        }
    }
    return active ? std::move(leaf) : nullptr;
}

/// Where f < 0: f's leaves' signs and its inside tiles, a bit a voxel (f itself is 32).
openvdb::BoolTree::Ptr insideOf(const openvdb::FloatTree& f) {
    using BoolLeaf = openvdb::BoolTree::LeafNodeType;
    std::vector<const FloatLeaf*> leaves;
    leaves.reserve(f.leafCount());
    f.getNodes(leaves);
    std::vector<BoolLeaf*> signs(leaves.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size()),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          for (std::size_t k = range.begin(); k != range.end(); ++k) {
                              signs[k] = new BoolLeaf(leaves[k]->origin(), false);
                              const float* values = leaves[k]->buffer().data();
                              for (openvdb::Index offset = 0; offset < FloatLeaf::SIZE; ++offset)
                                  if (values[offset] < 0.0f) signs[k]->setValueOnly(offset, true);
                          }
                      });
    auto inside = std::make_shared<openvdb::BoolTree>(false);
    for (BoolLeaf* leaf : signs) inside->addLeaf(leaf);
    auto tile = f.cbeginValueAll();
    tile.setMaxDepth(openvdb::FloatTree::ValueAllCIter::LEAF_DEPTH - 1);  // the tiles, not the leaves' voxels
    for (; tile; ++tile)
        if (*tile < 0.0f) inside->addTile(tile.getLevel(), tile.getCoord(), true, false);
    return inside;
}

}  // namespace

openvdb::FloatGrid::Ptr levelSetOfMesh(openvdb::FloatGrid::Ptr f, float bandWidth, const std::atomic<bool>& stop) {
    const Mesh mesh = meshOf(*f);
    const openvdb::BoolTree::Ptr inside = insideOf(f->tree());
    const openvdb::math::Transform::Ptr transform = f->transform().copy();
    const float voxelSize = float(f->voxelSize()[0]);
    f.reset();  // the caller's copy too, if it moved it here: its memory is the band's
    platform::releaseFreedMemory();
    if (stop) return nullptr;
    auto homes = std::make_unique<const Homes>(mesh);  // freed before the band, which does not use it
    platform::releaseFreedMemory();

    // The leaves that may hold near voxels: the homes and their neighbours.
    std::vector<std::uint64_t> leaves;
    leaves.reserve(homes->keys.size() * 4);
    for (std::uint64_t key : homes->keys) {
        const Coord origin = leafOrigin(key);
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz)
                    leaves.push_back(leafKey(origin.offsetBy(dx * kDim, dy * kDim, dz * kDim)));
    }
    tbb::parallel_sort(leaves.begin(), leaves.end());
    leaves.erase(std::unique(leaves.begin(), leaves.end()), leaves.end());
    // The large primitives can reach leaves no home neighbours: theirs too.
    for (std::uint32_t prim : homes->large)
        for (int half = 0; half < mesh.triangleCount(prim); ++half) {
            const Triangle t = mesh.triangle(prim, half);
            const Coord low =
                Coord::floor(openvdb::math::minComponent(t.a, openvdb::math::minComponent(t.b, t.c)) - 1.0);
            const Coord high =
                Coord::floor(openvdb::math::maxComponent(t.a, openvdb::math::maxComponent(t.b, t.c)) + 1.0);
            for (int x = low.x() & ~(kDim - 1); x <= high.x(); x += kDim)
                for (int y = low.y() & ~(kDim - 1); y <= high.y(); y += kDim)
                    for (int z = low.z() & ~(kDim - 1); z <= high.z(); z += kDim)
                        leaves.push_back(leafKey(Coord(x, y, z)));
        }
    if (!homes->large.empty()) {
        std::sort(leaves.begin(), leaves.end());
        leaves.erase(std::unique(leaves.begin(), leaves.end()), leaves.end());
    }

    std::vector<NearLeaf> near(leaves.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size(), 16),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          openvdb::tree::ValueAccessor<const openvdb::BoolTree> accessor(*inside);
                          for (std::size_t k = range.begin(); k != range.end(); ++k) {
                              if (stop.load(std::memory_order_relaxed)) return;
                              near[k] = nearVoxels(mesh, *homes, leaves[k], accessor);
                          }
                      });
    if (stop) return nullptr;
    homes.reset();
    {  // only the leaves that have near voxels (the others are most)
        std::size_t kept = 0;
        for (std::size_t k = 0; k < leaves.size(); ++k)
            if (!near[k].empty()) {
                leaves[kept] = leaves[k];
                near[kept++] = std::move(near[k]);
            }
        leaves.resize(kept);
        leaves.shrink_to_fit();
        near.resize(kept);
        near.shrink_to_fit();
    }
    platform::releaseFreedMemory();

    // The near voxels' leaves, by key (`leaves` is sorted).
    auto nearLeaf = [&](std::uint64_t key) -> const NearLeaf* {
        const auto at = std::lower_bound(leaves.begin(), leaves.end(), key);
        if (at == leaves.end() || *at != key) return nullptr;
        const NearLeaf& leaf = near[std::size_t(at - leaves.begin())];
        return leaf.empty() ? nullptr : &leaf;
    };
    // The band's leaves: those within the band's reach of the near voxels' leaves.
    const float band = std::max(bandWidth, 0.0f);
    const int reach = int(std::ceil(band)), around = (reach + kDim - 1) / kDim;
    std::vector<std::uint64_t> bandLeaves;
    for (const std::uint64_t key : leaves) {
        const Coord origin = leafOrigin(key);
        for (int dx = -around; dx <= around; ++dx)
            for (int dy = -around; dy <= around; ++dy)
                for (int dz = -around; dz <= around; ++dz)
                    bandLeaves.push_back(leafKey(origin.offsetBy(dx * kDim, dy * kDim, dz * kDim)));
    }
    tbb::parallel_sort(bandLeaves.begin(), bandLeaves.end());
    bandLeaves.erase(std::unique(bandLeaves.begin(), bandLeaves.end()), bandLeaves.end());

    std::vector<std::unique_ptr<FloatLeaf>> out(bandLeaves.size());
    ThreadScratch<BandBlock> blocks;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, bandLeaves.size(), 16),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          openvdb::tree::ValueAccessor<const openvdb::BoolTree> insideValues(*inside);
                          BandBlock& block = blocks.local();
                          for (std::size_t k = range.begin(); k != range.end(); ++k) {
                              if (stop.load(std::memory_order_relaxed)) return;
                              out[k] = bandLeaf(block, leafOrigin(bandLeaves[k]), reach, band, voxelSize, mesh,
                                                nearLeaf, insideValues);
                          }
                      });
    if (stop) return nullptr;
    near.clear();
    auto tree = std::make_shared<openvdb::FloatTree>(band * voxelSize);
    for (std::unique_ptr<FloatLeaf>& leaf : out)
        if (leaf) tree->addLeaf(leaf.release());
    // The tiles' signs, from the leaves' (leaves are level 0).
    openvdb::tools::signedFloodFillWithValues(*tree, band * voxelSize, -band * voxelSize, true, 1, 1);
    openvdb::tools::pruneLevelSet(*tree);

    openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(tree);
    grid->setTransform(transform);
    grid->setGridClass(openvdb::GRID_LEVEL_SET);
    return grid;
}

}  // namespace dqj
