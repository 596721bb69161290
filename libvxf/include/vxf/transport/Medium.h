// vxf — the participating medium of a voxel set: extinction and scattering per voxel.
#pragma once

#include <vxf/core/GridLookup.h>
#include <vxf/core/VoxelSet.h>
#include <vxf/core/Scene.h>

#include <openvdb/tools/Interpolation.h>

#include <set>
#include <string>

namespace vxf {

class RayScene;
class UniformBricks;

/// The medium's coefficients (1/world unit, RGB) at any point, per DESIGN.md:
/// σa(x) = density(x)·σa, σs(x) = density(x)·σs from the material, unless the voxel set
/// has per-voxel `sigma_a` / `sigma_s` (Vec3f) grids, which replace them. Lookups are
/// trilinear. Read-only and cheap to copy; give each thread its own Sampler.
/// A material of Henyey-Greenstein g ≠ 0 gives the transport's coefficients (transportScaling,
/// Phase.h): σs* = (1 − f)·σs, σt* = σt − f·σs, and the rest of the phase of mean cosine g*
/// (material().phaseG; for g > 0 delta-M of order 3, f = g⁴, g* = (g − f)/(1 − f); for g < 0 the
/// similarity relation, f = g, g* = 0), which the light stage, the accelerated sweeps and the
/// camera's read of their light take; isotropic() is the similarity relation's medium (σs(1 − g),
/// isotropic) for the transport that carries no angular moment; actual() the material's own
/// coefficients, for the camera's transmittance and its single scattering with the phase. With
/// g = 0 all three are the material's, bit for bit.
class Medium
{
public:
    /// How the Samplers read the grids. Dense: through dense copies of the density, surface and
    /// coefficient grids (each up to kDenseCopyBytes) and UniformBricks, for the marches that
    /// read them many times (the light stage, the gathers, the render). Trees: through the trees
    /// alone, no copies and no bricks, for a stage that reads each voxel a few times (the sweep
    /// kernel's lattice): the thick bunny's scatter at dim 256 held 113 MB of copies it never read
    /// after its setup. Either gives the same values.
    enum class Lookups { Dense, Trees };
    /// Uses `density` (required) and `sigma_a`, `sigma_s`, `surface` (optional) from @a set;
    /// throws vxf::Error when an optional grid has the wrong type or another transform.
    Medium(const VoxelSet& set, const Material& material, Lookups lookups = Lookups::Dense);
    /// The grids the constructor reads: `density`, `sigma_a`, `sigma_s`, `surface`.
    static const std::set<std::string>& gridsRead();

    /// The Henyey-Greenstein g of the material (0: isotropic), whichever coefficients this holds.
    double phaseG() const { return mActualMaterial.phaseG; }
    /// The same medium with the material's own coefficients (σs not reduced by the phase);
    /// a copy of this one when g = 0. Shares the grids and their dense copies.
    Medium actual() const;
    /// The same medium by the similarity relation: σs' = (1 − g)·σs, σt' = σt − g·σs and an
    /// isotropic phase (Phase.h), the transport of this one's for kernels that carry no angular
    /// moment; a copy of this one when g = 0.
    Medium isotropic() const;

    const openvdb::math::Transform& transform() const { return mDensity->transform(); }
    double voxelSize() const { return mDensity->voxelSize()[0]; }
    /// Index-space bounds of the medium (active density), empty when there is none.
    const openvdb::CoordBBox& activeBounds() const { return mBounds; }
    const openvdb::FloatGrid& density() const { return *mDensity; }
    /// The material of the coefficients held: the transport's (delta-M: σs*, and as
    /// phaseG the rest's mean cosine g*), isotropic()'s (σs', g 0) or actual()'s, the material
    /// itself. A Medium made from it takes it as a material of its own.
    const Material& material() const { return mMaterial; }
    /// The per-voxel coefficient grids, or null when the material's constants apply.
    const openvdb::Vec3SGrid* sigmaAGrid() const { return mSigmaA.get(); }
    const openvdb::Vec3SGrid* sigmaSGrid() const { return mSigmaS.get(); }
    /// The level set bounding the medium (sharp boundary), or null: then the medium ends where
    /// the interpolated density does. It is the voxel set's `surface` where that resolves the
    /// medium, and inside within a voxel of features too thin for it (about a voxel or less),
    /// whose voxels' volume fractions then carry the medium as without a surface.
    const openvdb::FloatGrid* surface() const { return mSurface.get(); }
    /// Where every march step is alike, uniform inside the surface or wholly outside it (marches
    /// cross those regions in one go), or null: with per-voxel `sigma_a`/`sigma_s` grids, or
    /// Lookups::Trees.
    const UniformBricks* uniformBricks() const { return mUniform.get(); }

    /// Per-thread trilinear lookups.
    class Sampler
    {
    public:
        explicit Sampler(const Medium& medium);
        const Medium& medium() const { return mMedium; }
        /// σt at index-space position @a ijk (1/world unit).
        openvdb::Vec3d sigmaT(const openvdb::Vec3d& ijk);
        /// σs at index-space position @a ijk (1/world unit).
        openvdb::Vec3d sigmaS(const openvdb::Vec3d& ijk);
        /// σs of voxel @a ijk itself, not interpolated (1/world unit).
        openvdb::Vec3d sigmaS(const openvdb::Coord& ijk);
        /// Signed distance to the surface at @a ijk (voxels, negative inside); −1 everywhere
        /// when the medium has no surface. Within kQuadraticBand of the surface it is read
        /// triquadratically (OpenVDB's QuadraticSampler, 27 voxels): the trilinear read of a
        /// distance that is convex where the surface is lies above it by up to dx²/8R, which
        /// moves a sphere's surface of radius R inward and shortened chords 0.1 voxel under
        /// its silhouette by 7.5% at R = 10 voxels (the bunny's convex silhouettes came out
        /// dark, its concave ones bright). Where the two reads differ by more than
        /// kQuadraticLimit the distance is not smooth over the 27 voxels (the kink over a
        /// medial axis: sheets and rims a voxel or two thick, surfaces curved tighter than
        /// about two voxels), and the parabola across it would move the surface, so the
        /// trilinear read stands there.
        double signedDistance(const openvdb::Vec3d& ijk);
        /// Sharp boundary: a voxel's coefficients and fluence-weighted emission are averages over
        /// its cube, of which only the volume fraction f = clamp(½ − φ/dx, 0, 1) lies inside the
        /// surface; dividing their trilinear interpolation by that of f gives the value inside
        /// the surface at @a ijk (exact for a uniform medium). Returns 1/max(f, kMinFraction);
        /// 1 without a surface.
        /// @a distanceBound: an upper bound of the signed distance (voxels) at @a ijk, so that
        /// points deep inside (all eight voxels whole) skip the lookups.
        double interiorScale(const openvdb::Vec3d& ijk, double distanceBound = 0.0);
        /// The surface's outward unit normal at @a ijk (central differences of signedDistance,
        /// one voxel apart) in @a normal; false without a surface or where the level set's
        /// slope is below 0.1 (not a distance there: a medial axis, the band's edge).
        bool surfaceNormal(const openvdb::Vec3d& ijk, openvdb::Vec3d& normal);
        /// Where voxel @a ijk's medium is: its centre, or where the centre lies outside the
        /// surface by less than half a voxel (the rim, whose medium is the part of its cube
        /// inside), the nearest point of the surface, c − φs·n. Its centre without a surface.
        openvdb::Vec3d mediumPoint(const openvdb::Coord& ijk);
        /// Whether voxel @a ijk is in the surface's skin, its centre within half a voxel of the
        /// surface on either side; then its nearest surface point c − φs·n in @a point and the
        /// outward normal in @a normal. The scatter passes gather a skin voxel's fluence there,
        /// so the field's values on the surface are known wherever the surface is (SourceField).
        bool skinPoint(const openvdb::Coord& ijk, openvdb::Vec3d& point, openvdb::Vec3d& normal);

        /// Take the surface's crossings (InsideSteps) on @a boundary, the meshes the level set
        /// was made from (world units; null: the level set alone). A ray that grazes the
        /// surface crosses the medium along a chord c = 2√(2Rδ) for a depth δ under the
        /// tangent, so dc/dδ = 4R/c: 100 at R = 32 voxels and a chord of a voxel. The level set
        /// holds a mesh's surface to a few thousandths of a voxel (a polyhedron's distance is
        /// not smooth over its edges), and along grazing shadow rays that came to optical
        /// depths up to 0.34 off on a coarse polyhedral sphere (TransmittanceTest), 1e-3 with
        /// the mesh. The level set still decides what is inside (open and non-manifold meshes
        /// stay well-posed): the meshes only place the crossings it finds (snapCrossing), and
        /// one it missed within a step near the surface (boundaryHit). Costs two or three
        /// Embree rays per crossing: for the render's camera and shadow rays and the light
        /// stage's, not the scatter passes' gathers. On the thick bunny (point light, 1.3
        /// voxels per mean free path) the image came 3.94 -> 3.79% off the reference at 64
        /// voxels across, 2.067 -> 2.057% at 96. With MissedCrossings::Ignored the meshes only
        /// place the crossings the level set finds: no Embree ray for every step near the
        /// surface (the light stage, whose marches end at voxel centres: docs/accuracy-notes.md (ao)).
        enum class MissedCrossings {
            Found, ///< boundaryHit asks the meshes along every step near the surface
            Ignored, ///< boundaryHit finds none
        };
        void snapCrossingsTo(const RayScene* boundary, MissedCrossings missed = MissedCrossings::Found)
        {
            mBoundary = boundary;
            mFindMissed = missed == MissedCrossings::Found;
        }
        /// The crossing of the surface near the level set's @a t on the index-space ray @a origin +
        /// t·@a direction (unit), into the medium when @a entering: the nearest hit of the
        /// boundary meshes of that kind (an outward-oriented mesh met from its front, or from
        /// behind when leaving) within kSnapWindow voxels of depth (kSnapWindow / cos along a
        /// ray meeting the surface at cosine cos, at most kSnapReach), clamped to [@a lo, @a hi];
        /// @a t itself without boundary meshes or such a hit.
        double snapCrossing(const openvdb::Vec3d& origin, const openvdb::Vec3d& direction, double t, double lo, double hi, bool entering);
        /// The first hit @a t of the boundary meshes on the index-space ray in (@a lo, @a hi),
        /// and whether the ray @a entering the meshes there; false without boundary meshes or a
        /// hit, or where missed crossings are ignored (snapCrossingsTo).
        bool boundaryHit(
            const openvdb::Vec3d& origin, const openvdb::Vec3d& direction, double lo, double hi, double& t, bool& entering) const;

    private:
        const Medium& mMedium;
        const RayScene* mBoundary = nullptr;
        bool mFindMissed = true;
        GridLookup<openvdb::FloatGrid> mDensity;
        std::optional<GridLookup<openvdb::Vec3SGrid>> mSigmaA, mSigmaS;
        std::optional<GridLookup<openvdb::FloatGrid>> mSurface;
    };

    /// Voxels: signedDistance reads triquadratically where the trilinear read is within this
    /// of the surface. Beyond it the two reads cannot disagree on the side (they would differ
    /// by more than kQuadraticLimit), and the zero crossings are found within it.
    static constexpr double kQuadraticBand = 0.25;
    static constexpr double kQuadraticLimit = 0.125; ///< voxels: ½·(2/R)·¼, R = 2 voxels

    /// interiorScale's floor on the volume fraction (where an edit put density outside the surface).
    static constexpr double kMinFraction = 0.1;

    /// Voxels: how far from the level set's crossing Sampler::snapCrossing looks for the mesh's.
    static constexpr double kSnapWindow = 0.5;
    /// Voxels: the farthest along a ray Sampler::snapCrossing looks (grazing rays).
    static constexpr double kSnapReach = 2.0;

private:
    /// Hold the material's σs (and a `sigma_s` grid's) times @a factor, with phase g @a restG.
    void scaleScattering(double factor, double restG);

    openvdb::FloatGrid::ConstPtr mDensity;
    openvdb::Vec3SGrid::ConstPtr mSigmaA, mSigmaS;
    openvdb::FloatGrid::ConstPtr mSurface;
    /// Dense copies of density and surface for the marches' lookups (null: too large, read the trees).
    std::shared_ptr<const DenseCopy<openvdb::FloatGrid>> mDensityDense, mSurfaceDense;
    /// The same of the `sigma_a` and `sigma_s` grids (several media): their reads through
    /// accessors were a third of the grapes example's render; mActualSigmaSDense is actual()'s.
    std::shared_ptr<const DenseCopy<openvdb::Vec3SGrid>> mSigmaADense, mSigmaSDense, mActualSigmaSDense;
    std::shared_ptr<const UniformBricks> mUniform;
    Material mMaterial;
    /// The material and `sigma_s` grid as given, which actual() holds (the scaled ones above).
    Material mActualMaterial;
    openvdb::Vec3SGrid::ConstPtr mActualSigmaS;
    openvdb::CoordBBox mBounds;
};

/// File metadata key recording the material a set was lit with (JSON {"sigma_a": [r,g,b],
/// "sigma_s": [r,g,b]}), so later stages read it from the file itself.
inline constexpr const char* kMaterialMetaKey = "vxf:material";

/// Record @a material in @a set's file metadata.
void recordMaterial(VoxelSet& set, const Material& material);

/// The material recorded in @a set (throws vxf::Error naming the key when absent).
Material recordedMaterial(const VoxelSet& set);

} // namespace vxf
