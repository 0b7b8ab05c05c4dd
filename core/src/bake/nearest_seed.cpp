// The nearest seed of every voxel of a region (nearest_seed.hpp).
#include "bake/nearest_seed.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <unordered_map>

#include <openvdb/tools/Prune.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "platform/thread_scratch.hpp"

namespace dqj {
namespace {

using IdLeaf = openvdb::Int32Tree::LeafNodeType;
constexpr std::uint64_t kNone = std::numeric_limits<std::uint64_t>::max();
constexpr std::int32_t kUnreached = -1;
// During a round a claimed voxel holds claim(its seed): kClaimed if it had none, else -3 - seed.
constexpr std::int32_t kClaimed = -2;
constexpr std::int32_t claim(std::int32_t seed) { return seed >= 0 ? -3 - seed : kClaimed; }
/// The seed a slot's value stands for, claimed or not; negative: none yet.
constexpr std::int32_t seedOf(std::int32_t value) { return value <= -3 ? -3 - value : value; }

/// The 26 neighbours' steps.
constexpr std::array<std::array<int, 3>, 26> kSteps = [] {
    std::array<std::array<int, 3>, 26> steps{};
    std::size_t count = 0;
    for (int x = -1; x <= 1; ++x)
        for (int y = -1; y <= 1; ++y)
            for (int z = -1; z <= 1; ++z)
                if (x != 0 || y != 0 || z != 0) steps[count++] = {x, y, z};
    return steps;
}();

/// The region's voxels as slots: voxel `offset` of leaf k is slot k * 512 + offset. Each leaf
/// knows its 26 neighbour leaves, so a step to a neighbour voxel needs no tree look-up.
class Slots {
public:
    explicit Slots(openvdb::Int32Tree& tree) {
        tree.getNodes(leaves_);
        std::unordered_map<const IdLeaf*, std::int32_t> index;
        index.reserve(leaves_.size());
        for (std::size_t k = 0; k < leaves_.size(); ++k) index.emplace(leaves_[k], std::int32_t(k));
        if (leaves_.size() >= std::size_t(std::numeric_limits<std::int32_t>::max()))
            throw std::length_error("nearestSeeds: too many leaves");
        around_.resize(leaves_.size());
        values_.resize(leaves_.size());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves_.size()),
                          [&](const tbb::blocked_range<std::size_t>& range) {
                              openvdb::tree::ValueAccessor<const openvdb::Int32Tree> accessor(tree);
                              for (std::size_t k = range.begin(); k != range.end(); ++k) {
                                  values_[k] = leaves_[k]->buffer().data();
                                  for (int cell = 0; cell < 27; ++cell) {
                                      constexpr int kDim = int(IdLeaf::DIM);
                                      const openvdb::Coord step((cell / 9 - 1) * kDim, (cell / 3 % 3 - 1) * kDim,
                                                                (cell % 3 - 1) * kDim);
                                      const IdLeaf* leaf = accessor.probeConstLeaf(leaves_[k]->origin() + step);
                                      around_[k][cell] = leaf ? index.at(leaf) : -1;
                                  }
                              }
                          });
    }

    std::size_t leafCount() const { return leaves_.size(); }
    IdLeaf& leaf(std::size_t k) const { return *leaves_[k]; }

    /// The slot of the active voxel one step (each of dx, dy, dz in -1..1) from `slot`, or kNone.
    std::uint64_t step(std::uint64_t slot, int dx, int dy, int dz) const {
        const auto offset = unsigned(slot % IdLeaf::SIZE);
        const int x = int(offset >> 6) + dx, y = int((offset >> 3) & 7u) + dy, z = int(offset & 7u) + dz;
        // x >> 3 is -1, 0 or 1: the neighbour leaf along x (arithmetic shift, C++20).
        const std::int32_t leaf = around_[slot / IdLeaf::SIZE][((x >> 3) + 1) * 9 + ((y >> 3) + 1) * 3 + (z >> 3) + 1];
        if (leaf < 0) return kNone;
        const unsigned to = (unsigned(x & 7) << 6) | (unsigned(y & 7) << 3) | unsigned(z & 7);
        if (!leaves_[std::size_t(leaf)]->isValueOn(to)) return kNone;
        return std::uint64_t(leaf) * IdLeaf::SIZE + to;
    }

    /// The seed index a slot holds, for reading and writing while other threads do.
    std::atomic_ref<std::int32_t> id(std::uint64_t slot) const {
        return std::atomic_ref<std::int32_t>(values_[slot / IdLeaf::SIZE][slot % IdLeaf::SIZE]);
    }

    openvdb::Coord coord(std::uint64_t slot) const {
        return leaves_[slot / IdLeaf::SIZE]->offsetToGlobalCoord(openvdb::Index(slot % IdLeaf::SIZE));
    }

private:
    std::vector<IdLeaf*> leaves_;
    std::vector<std::array<std::int32_t, 27>> around_;
    std::vector<std::int32_t*> values_;
};

}  // namespace

openvdb::Int32Tree::Ptr nearestSeeds(const openvdb::MaskTree& region, const std::vector<openvdb::Coord>& voxels,
                                     const std::vector<openvdb::Vec3f>& points, int rounds) {
    if (voxels.size() != points.size()) throw std::invalid_argument("nearestSeeds: as many voxels as points");
    if (rounds < 0) throw std::invalid_argument("nearestSeeds: a negative count of rounds");
    if (voxels.size() >= std::size_t(std::numeric_limits<std::int32_t>::max()))
        throw std::length_error("nearestSeeds: too many seeds");
    auto ids = std::make_shared<openvdb::Int32Tree>(region, kUnreached, openvdb::TopologyCopy());
    const Slots slots(*ids);

    // Layer 0: the seeds' own voxels.
    std::vector<std::uint64_t> layer;
    {
        openvdb::tree::ValueAccessor<const openvdb::Int32Tree> accessor(*ids);
        std::unordered_map<const IdLeaf*, std::uint64_t> first;  // leaf -> its first slot
        first.reserve(slots.leafCount());
        for (std::size_t k = 0; k < slots.leafCount(); ++k) first.emplace(&slots.leaf(k), k * IdLeaf::SIZE);
        for (std::size_t seed = 0; seed < voxels.size(); ++seed) {
            const IdLeaf* leaf = accessor.probeConstLeaf(voxels[seed]);
            if (!leaf || !leaf->isValueOn(voxels[seed])) continue;
            const std::uint64_t slot = first.at(leaf) + IdLeaf::coordToOffset(voxels[seed]);
            if (slots.id(slot).load(std::memory_order_relaxed) != kUnreached) continue;
            slots.id(slot).store(std::int32_t(seed), std::memory_order_relaxed);
            layer.push_back(slot);
        }
    }

    // Each further round: the neighbours of the voxels that changed in the last one which are
    // unreached or nearer to such a voxel's seed than to their own (claimed once each, in any
    // order), then each one's nearest seed of its own and its neighbours' (read only, so the
    // result does not depend on the order), then those that changed written. Reached voxels are
    // taken up again because the rounds are layers of 26-neighbour steps, not of distance: a
    // voxel first reached from one seed may be nearer to another that arrives a round later.
    // Every change brings a voxel nearer to its seed, so the rounds end; `rounds` ends them
    // sooner. Each round's outcome depends only on the voxels' and their neighbours' values before
    // it (claims only mark; the choice reads, then writes), never on the order of the work.
    ThreadScratch<std::vector<std::uint64_t>> claims;
    std::vector<std::int32_t> chosen;
    auto squared = [&](const openvdb::Vec3f& at, std::int32_t seed) {
        return (at - points[std::size_t(seed)]).lengthSqr();
    };
    for (int round = 0; round < rounds && !layer.empty(); ++round) {
        tbb::parallel_for(
            tbb::blocked_range<std::size_t>(0, layer.size(), 1024), [&](const tbb::blocked_range<std::size_t>& range) {
                std::vector<std::uint64_t>& claimed = claims.local();
                for (std::size_t index = range.begin(); index != range.end(); ++index) {
                    const std::int32_t seed = seedOf(slots.id(layer[index]).load(std::memory_order_relaxed));
                    const openvdb::Vec3f from = slots.coord(layer[index]).asVec3s();
                    for (const auto& [dx, dy, dz] : kSteps) {
                        const std::uint64_t next = slots.step(layer[index], dx, dy, dz);
                        if (next == kNone) continue;
                        auto id = slots.id(next);
                        std::int32_t current = id.load(std::memory_order_relaxed);
                        if (current == seed || current == kClaimed || current <= -3) continue;
                        const openvdb::Vec3f at = from + openvdb::Vec3f(float(dx), float(dy), float(dz));
                        const bool take = current == kUnreached || squared(at, seed) < squared(at, current);
                        if (take && id.compare_exchange_strong(current, claim(current), std::memory_order_relaxed))
                            claimed.push_back(next);
                    }
                }
            });
        layer.clear();
        for (std::vector<std::uint64_t>& claimed : claims) {
            layer.insert(layer.end(), claimed.begin(), claimed.end());
            claimed.clear();
        }
        // In slot order, so that neighbouring voxels are worked on together (in the claims'
        // order, nearly every step was a cache miss).
        tbb::parallel_sort(layer.begin(), layer.end());
        chosen.resize(layer.size());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, layer.size(), 1024),
                          [&](const tbb::blocked_range<std::size_t>& range) {
                              for (std::size_t index = range.begin(); index != range.end(); ++index) {
                                  const std::uint64_t slot = layer[index];
                                  const openvdb::Vec3f at = slots.coord(slot).asVec3s();
                                  std::int32_t best = seedOf(slots.id(slot).load(std::memory_order_relaxed));
                                  float nearest =
                                      best >= 0 ? squared(at, best) : std::numeric_limits<float>::infinity();
                                  for (const auto& [dx, dy, dz] : kSteps) {
                                      const std::uint64_t from = slots.step(slot, dx, dy, dz);
                                      if (from == kNone) continue;
                                      const std::int32_t seed = seedOf(slots.id(from).load(std::memory_order_relaxed));
                                      if (seed < 0 || seed == best) continue;
                                      const float distance = squared(at, seed);
                                      if (distance < nearest || (distance == nearest && seed < best)) {
                                          nearest = distance;
                                          best = seed;
                                      }
                                  }
                                  chosen[index] = best;
                              }
                          });
        // Written; what kept its seed leaves the round.
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, layer.size(), 4096),
                          [&](const tbb::blocked_range<std::size_t>& range) {
                              for (std::size_t index = range.begin(); index != range.end(); ++index) {
                                  auto id = slots.id(layer[index]);
                                  if (seedOf(id.load(std::memory_order_relaxed)) == chosen[index]) layer[index] = kNone;
                                  id.store(chosen[index], std::memory_order_relaxed);
                              }
                          });
        std::erase(layer, kNone);
    }

    // What no seed reached is not part of the result.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, slots.leafCount()),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          for (std::size_t k = range.begin(); k != range.end(); ++k) {
                              IdLeaf& leaf = slots.leaf(k);
                              for (auto on = leaf.beginValueOn(); on; ++on)
                                  if (*on < 0) leaf.setValueOff(on.pos());
                          }
                      });
    openvdb::tools::pruneInactive(*ids);  // leaves no seed reached at all
    return ids;
}

}  // namespace dqj
