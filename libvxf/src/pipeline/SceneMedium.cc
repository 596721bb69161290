#include <vxf/pipeline/SceneMedium.h>

#include <vxf/io/VoxelSetFile.h>
#include <vxf/pipeline/SceneGeometry.h>

#include <openvdb/tools/Composite.h>
#include <openvdb/tools/GridTransformer.h>

#include <fmt/format.h>

namespace vxf {

int mediaCount(const Scene& scene)
{
    int n = 0;
    for (const auto& o : scene.objects) n += o.role == SceneObject::Role::Medium ? 1 : 0;
    return n;
}

Material sceneMaterial(const Scene& scene)
{
    std::optional<Material> result;
    for (const auto& o : scene.objects) {
        if (o.role != SceneObject::Role::Medium) continue;
        if (!result) {
            result = *o.material;
            continue;
        }
        for (int c = 0; c < 3; ++c) {
            result->sigmaA[c] = std::max(result->sigmaA[c], o.material->sigmaA[c]);
            result->sigmaS[c] = std::max(result->sigmaS[c], o.material->sigmaS[c]);
        }
    }
    if (!result) throw UsageError(fmt::format("{}: no object is a medium", scene.path));
    return *result;
}

void attachMaterialGrids(VoxelSet& set, const Material& material)
{
    if (material.gridsFile.empty()) return;
    const VoxelSet source = readVoxelSet(material.gridsFile);
    for (const auto& [role, name] : {std::pair<std::string, std::string>{"sigma_a", material.sigmaAGrid}, {"sigma_s", material.sigmaSGrid}}) {
        if (name.empty()) continue;
        auto grid = source.find(name);
        if (!grid) throw InputError(material.gridsFile, 0, 0, fmt::format("no grid named '{}' (for {})", name, role));
        auto typed = openvdb::gridPtrCast<openvdb::Vec3SGrid>(grid);
        if (!typed) {
            throw InputError(material.gridsFile, 0, 0, fmt::format("grid '{}' holds {} values; {} needs vec3s", name, grid->valueType(), role));
        }
        openvdb::Vec3SGrid::Ptr placed;
        if (typed->transform() == set.transform()) {
            placed = typed->deepCopy();
        } else {
            placed = openvdb::Vec3SGrid::create(typed->background());
            placed->setTransform(set.transformPtr());
            openvdb::tools::resampleToMatch<openvdb::tools::BoxSampler>(*typed, *placed);
        }
        placed->setName(role);
        set.put(placed);
    }
}

VoxelSet voxelizeMedia(const Scene& scene, const VoxelizeOptions& options, Interrupter* interrupter)
{
    std::vector<const SceneObject*> media;
    for (const auto& o : scene.objects) {
        if (o.role == SceneObject::Role::Medium) media.push_back(&o);
    }
    if (media.empty()) throw UsageError(fmt::format("{}: no object is a medium", scene.path));
    if (media.size() == 1) {
        VoxelSet set = voxelize(objectMesh(*media.front()), options, interrupter);
        attachMaterialGrids(set, *media.front()->material);
        return set;
    }
    for (const SceneObject* o : media) {
        if (!o->material->gridsFile.empty()) {
            throw UsageError(fmt::format("{}: object '{}': per-voxel coefficient grids need the scene's only medium "
                                         "(it has {})", scene.path, o->name, media.size()));
        }
    }

    std::vector<TriangleMesh> meshes;
    openvdb::BBoxd bounds;
    for (const SceneObject* o : media) {
        meshes.push_back(objectMesh(*o));
        bounds.expand(meshes.back().bounds());
    }
    VoxelizeOptions onLattice = options;
    onLattice.lattice = voxelLattice(bounds, resolveVoxelSize(bounds, options));

    openvdb::FloatGrid::Ptr surface, density;
    openvdb::Vec3SGrid::Ptr sigmaA, sigmaS;
    for (std::size_t i = 0; i < media.size(); ++i) {
        VoxelSet one = voxelize(meshes[i], onLattice, interrupter);
        auto s = one.get<openvdb::FloatGrid>("surface");
        auto d = one.get<openvdb::FloatGrid>("density");
        // σ_i(x) = density_i(x)·σ_i on density_i's topology (tiles stay tiles).
        const Material& m = *media[i]->material;
        const auto coefficients = [&d](const openvdb::Vec3d& sigma) {
            auto grid = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
            grid->setTransform(d->transformPtr());
            grid->tree().topologyUnion(d->tree());
            const openvdb::Vec3f base(sigma);
            auto densityAt = d->getConstAccessor();
            for (auto it = grid->beginValueOn(); it; ++it) it.setValue(base * densityAt.getValue(it.getCoord()));
            return grid;
        };
        auto a = coefficients(m.sigmaA), sc = coefficients(m.sigmaS);
        if (i == 0) {
            surface = s;
            density = d;
            sigmaA = a;
            sigmaS = sc;
        } else {
            openvdb::tools::csgUnion(*surface, *s);
            openvdb::tools::compMax(*density, *d);
            openvdb::tools::compSum(*sigmaA, *a);
            openvdb::tools::compSum(*sigmaS, *sc);
        }
    }
    VoxelSet set(surface->transformPtr());
    surface->setName("surface");
    density->setName("density");
    sigmaA->setName("sigma_a");
    sigmaS->setName("sigma_s");
    set.put(surface);
    set.put(density);
    set.put(sigmaA);
    set.put(sigmaS);
    return set;
}

} // namespace vxf
