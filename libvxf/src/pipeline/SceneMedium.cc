#include <vxf/pipeline/SceneMedium.h>

#include <vxf/core/GridRoles.h>
#include <vxf/io/VoxelPlacement.h>
#include <vxf/io/VoxelSetFile.h>
#include <vxf/pipeline/SceneGeometry.h>

#include <openvdb/tools/Composite.h>
#include <openvdb/tools/GridTransformer.h>
#include <openvdb/tools/MultiResGrid.h>
#include <openvdb/tools/Prune.h>

#include <fmt/format.h>

#include <cmath>

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
    const VoxelSet source = readGrids(material.gridsFile, {material.sigmaAGrid, material.sigmaSGrid});
    for (const auto& [role, name] :
        {std::pair<std::string, std::string>{"sigma_a", material.sigmaAGrid}, {"sigma_s", material.sigmaSGrid}}) {
        if (name.empty()) continue;
        auto grid = source.find(name);
        if (!grid) throw InputError(material.gridsFile, 0, 0, fmt::format("no grid named '{}' (for {})", name, role));
        auto typed = openvdb::gridPtrCast<openvdb::Vec3SGrid>(grid);
        if (!typed) {
            throw InputError(
                material.gridsFile, 0, 0, fmt::format("grid '{}' holds {} values; {} needs vec3s", name, grid->valueType(), role));
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

namespace {

/// How many halvings of a volume's voxels (@a dx wide, @a widest along its longest side) @a options
/// ask for: the power of two nearest the asked voxel size (voxel_size, or the longest side over
/// dim), never finer than the grid's own and never below two voxels across.
int volumeHalvings(const VoxelizeOptions& options, double dx, int widest)
{
    const double ratio = options.voxelSize > 0.0 ? options.voxelSize / dx : options.dim > 0 ? double(widest) / options.dim : 1.0;
    if (!(ratio > 1.0)) return 0;
    const int most = std::max(0, int(std::floor(std::log2(std::max(widest, 1)))) - 1);
    return std::min(int(std::lround(std::log2(ratio))), most);
}

/// @a density coarsened @a halvings times by OpenVDB's MultiResGrid (full-weighting restriction:
/// each coarse voxel the tent-weighted mean of the 3³ fine ones around it, so the medium's mass,
/// Σ density·dx³, is kept), on the transform whose voxel 0 is the fine voxel 0 and whose voxels are
/// 2^halvings as wide. Its tree is taken (@a density is left empty); uniform regions become tiles.
openvdb::FloatGrid::Ptr coarsened(openvdb::FloatGrid::Ptr density, int halvings)
{
    openvdb::math::Transform::Ptr transform = density->transform().copy();
    transform->preScale(double(1 << halvings));
    openvdb::tools::MultiResGrid<openvdb::FloatTree> pyramid(std::size_t(halvings) + 1, density);
    auto coarse = openvdb::FloatGrid::create(pyramid.treePtr(std::size_t(halvings)));
    coarse->setTransform(transform);
    openvdb::tools::prune(coarse->tree());
    return coarse;
}

/// A volume object's medium: its grid as `density`, on its own voxels moved by the object's
/// transform (resampled trilinearly onto axis-aligned cubic voxels of the same volume when
/// that turns or stretches them), negative values (simulations leave some after advection)
/// clamped to 0, without a `surface`; coarsened by halvings (coarsened()) when @a options ask for
/// a voxel size or dim, and @a note then says so. Throws vxf::InputError naming the file and grid.
VoxelSet volumeMedium(const SceneObject& object, const VoxelizeOptions& options, std::string* note)
{
    const VoxelSet file = readGrids(object.volume, {object.grid}); // not the file's other grids (velocities)
    const auto fail = [&](const std::string& what) { throw InputError(object.volume, 0, 0, what); };
    const openvdb::GridBase::Ptr found = file.find(object.grid);
    if (!found) {
        std::string names;
        for (const std::string& name : voxelGridNames(object.volume)) names += (names.empty() ? "" : ", ") + name;
        fail(
            fmt::format("no grid named '{}' for object '{}' (the file has: {})", object.grid, object.name, names.empty() ? "none" : names));
    }
    const auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(found);
    if (!grid) fail(fmt::format("grid '{}' holds {} values; a density is float", object.grid, found->valueType()));
    if (grid->getGridClass() == openvdb::GRID_LEVEL_SET) {
        fail(fmt::format("grid '{}' is a level set (signed distances), not a density; make a fog volume of it "
                         "(vdb_tool -ls2fog, OpenVDB's sdfToFogVolume) or give the mesh",
            object.grid));
    }
    if (grid->background() != 0.0f) {
        fail(fmt::format(
            "grid '{}' has background {}; a density's is 0 (the medium would fill all space)", object.grid, grid->background()));
    }
    openvdb::FloatGrid::Ptr density = grid->deepCopy();
    bool finite = true;
    for (auto it = density->beginValueOn(); it; ++it) {
        const float v = *it;
        if (!std::isfinite(v))
            finite = false;
        else if (v < 0.0f)
            it.setValue(0.0f);
    }
    if (!finite) fail(fmt::format("grid '{}' holds a non-finite density", object.grid));

    openvdb::math::Transform::Ptr moved =
        placedTransform(grid->transform(), resolvePlacement(object.placement, object.volume, file.metadata()).placement);
    if (object.objectToWorld != openvdb::Mat4d::identity()) moved->postMult(object.objectToWorld);
    density->setTransform(moved);
    // Cubic, axis-aligned voxels, which the marches and sweeps take (one voxel size).
    const openvdb::Vec3d size = moved->voxelSize();
    const bool cubic =
        moved->isLinear() && moved->hasUniformScale() && openvdb::math::isDiagonal(moved->baseMap()->getAffineMap()->getMat4().getMat3());
    if (!cubic) {
        auto target = openvdb::FloatGrid::create(0.0f);
        target->setTransform(openvdb::math::Transform::createLinearTransform(std::cbrt(size[0] * size[1] * size[2])));
        openvdb::tools::resampleToMatch<openvdb::tools::BoxSampler>(*density, *target);
        density = target;
    }
    const openvdb::CoordBBox box = density->evalActiveVoxelBoundingBox();
    const int widest = box.empty() ? 0 : std::max({box.dim().x(), box.dim().y(), box.dim().z()});
    const double dx = density->voxelSize()[0];
    if (const int halvings = volumeHalvings(options, dx, widest); halvings > 0) {
        density = coarsened(density, halvings);
        if (note) {
            *note = fmt::format("'{}' solved at voxel size {:.4g}, its own {:.4g} coarsened {}x ({} voxels along its longest "
                                "side, {} asked)",
                object.name, dx * (1 << halvings), dx, 1 << halvings, (widest + (1 << halvings) - 1) >> halvings,
                options.voxelSize > 0.0 ? fmt::format("voxel size {:.4g}", options.voxelSize) : fmt::format("dim {}", options.dim));
        }
    } else if (note && (options.dim > 0 || options.voxelSize > 0.0)) {
        *note = fmt::format("'{}' solved on its own voxels ({:.4g} wide, {} along its longest side): a volume is coarsened by "
                            "halvings, never refined",
            object.name, dx, widest);
    }
    density->setName(grids::kDensity);
    density->setGridClass(openvdb::GRID_FOG_VOLUME);
    VoxelSet set(density->transformPtr());
    set.put(density);
    return set;
}

} // namespace

VoxelizeOptions sceneVoxelizeOptions(const SceneSettings& settings)
{
    VoxelizeOptions options;
    options.voxelSize = settings.voxelSize;
    options.dim = settings.voxelSize > 0.0 ? 0 : settings.dim;
    options.bandWidth = float(settings.band);
    return options;
}

openvdb::BBoxd volumeBounds(const SceneObject& object)
{
    const VoxelSet set = volumeMedium(object, VoxelizeOptions{}, nullptr);
    const auto density = set.get<openvdb::FloatGrid>(grids::kDensity);
    const openvdb::CoordBBox box = density->evalActiveVoxelBoundingBox();
    return box.empty() ? openvdb::BBoxd() : density->transform().indexToWorld(box);
}

VoxelSet voxelizeMedia(const Scene& scene, const VoxelizeOptions& options, Interrupter* interrupter, std::string* note)
{
    std::vector<const SceneObject*> media;
    for (const auto& o : scene.objects) {
        if (o.role == SceneObject::Role::Medium) media.push_back(&o);
    }
    if (media.empty()) throw UsageError(fmt::format("{}: no object is a medium", scene.path));
    for (const SceneObject* o : media) {
        if (o->isVolume() && media.size() > 1) {
            throw UsageError(fmt::format(
                "{}: object '{}': a volume object must be the scene's only medium (it has {})", scene.path, o->name, media.size()));
        }
    }
    if (media.size() == 1 && media.front()->isVolume()) {
        VoxelSet set = volumeMedium(*media.front(), options, note);
        attachMaterialGrids(set, *media.front()->material);
        return set;
    }
    if (media.size() == 1) {
        VoxelSet set = voxelize(objectMesh(*media.front()), options, interrupter);
        attachMaterialGrids(set, *media.front()->material);
        return set;
    }
    for (const SceneObject* o : media) {
        if (!o->material->gridsFile.empty()) {
            throw UsageError(fmt::format("{}: object '{}': per-voxel coefficient grids need the scene's only medium "
                                         "(it has {})",
                scene.path, o->name, media.size()));
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
        auto s = one.get<openvdb::FloatGrid>(grids::kSurface);
        auto d = one.get<openvdb::FloatGrid>(grids::kDensity);
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
    surface->setName(grids::kSurface);
    density->setName(grids::kDensity);
    sigmaA->setName(grids::kSigmaA);
    sigmaS->setName(grids::kSigmaS);
    set.put(surface);
    set.put(density);
    set.put(sigmaA);
    set.put(sigmaS);
    return set;
}

} // namespace vxf
