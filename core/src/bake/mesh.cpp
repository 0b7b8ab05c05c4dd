// Meshes of the baked surface (mesh.hpp): the mesher (mesh_stream.hpp) into memory or into a
// PLY, OBJ, STL or 3MF file (mesh_file.hpp).
#include "dqjulia/mesh.hpp"

#include "bake/mesh_file.hpp"
#include "bake/mesh_stream.hpp"
#include "bake/print_check.hpp"

namespace dqj {

std::vector<std::uint32_t> Mesh::triangulated() const {
    std::vector<std::uint32_t> indices;
    indices.reserve(3 * triangleCount());
    for (const auto& triangle : triangles) indices.insert(indices.end(), triangle.begin(), triangle.end());
    for (const auto& quad : quads) {
        indices.insert(indices.end(), {quad[0], quad[1], quad[2]});
        indices.insert(indices.end(), {quad[0], quad[2], quad[3]});
    }
    return indices;
}

Mesh bakeMesh(const Params& params, const BakeOptions& options, const ProgressCallback& progress, BakeStats* statsOut) {
    validate(params);
    Mesh mesh;
    auto append = [&mesh](Mesh&& part) {
        if (mesh.positions.empty() && mesh.quads.empty() && mesh.triangles.empty()) {
            mesh = std::move(part);  // one piece: taken over, never copied
            return;
        }
        auto add = [](auto& to, auto& from) {
            to.insert(to.end(), from.begin(), from.end());
            from = {};
        };
        add(mesh.positions, part.positions);
        add(mesh.normals, part.normals);
        add(mesh.colors, part.colors);
        add(mesh.triangles, part.triangles);
        add(mesh.quads, part.quads);
    };
    BakeStats stats;
    meshSurface(params, options, progress, append, stats);
    if (progress && !progress(1.0)) throw Cancelled();
    if (statsOut) *statsOut = stats;
    return mesh;
}

MeshCounts bakeMeshFile(const Params& params, const std::string& path, const BakeOptions& options,
                        const ProgressCallback& progress, BakeStats* stats, const MeshScale& scale) {
    return bakeMeshFileChecked(params, path, options, progress, stats, scale, {});
}

void writeMesh(const Mesh& mesh, const std::string& path, Existing existing, const MeshScale& scale) {
    MeshFile file(path, !mesh.colors.empty(), existing, scale);
    file.add(mesh);
    file.commit();
}

}  // namespace dqj
