// vxf — the voxels a transport sweep runs over, as flat per-leaf arrays (private to libvxf).
#pragma once

#include <vxf/core/Hash.h>
#include <vxf/core/Interrupter.h>
#include <vxf/transport/Medium.h>
#include <vxf/transport/Phase.h>

#include "core/ScratchArray.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <unordered_map>
#include <vector>

namespace vxf::detail {

/// The leaves of a voxel set's medium and of a source grid (their active topology, tiles
/// voxelized), each held as 8³ values in flat arrays, with the 26 neighbouring leaves of each
/// and their order along every octant of directions. Built once per solve: σt and σs per voxel
/// (the medium's own values, density × material or the `sigma_a`/`sigma_s` grids) and the
/// surface's signed distance are read here, so a sweep reads memory, not trees.
///
/// Sharp boundary, as the gathers have it: with a surface, a voxel's values are averages over
/// its cube of which the fraction f = clamp(½ − φ/dx, 0, 1) lies inside, so the medium inside
/// holds σt/f and J/f (f at least Medium::kMinFraction), and a sweep's step carries the medium
/// only over its part inside the surface (the signed distance linear along the step). Without
/// a surface every voxel is whole (f = 1) and the density's own ramp is the edge.
///
/// Arrays "per voxel" hold voxelCount() values: voxel (x, y, z) of fine leaf n at
/// n·512 + x·64 + y·8 + z, then one value for each coarse leaf (Tiles::Coarse: an 8³ block of
/// a tile swept as one cell), after the fine leaves' (voxelStart). "Padded" arrays hold 1000 per
/// fine leaf: the leaf and one voxel of each neighbour around it, local coordinates −1…8
/// (paddedIndex), so that a voxel's upwind reads stay inside its leaf's block (a coarse
/// neighbour's voxels all its one value). Voxels of no leaf read as vacuum (σt = 0, J = 0).
///
/// Coarse cells (variable resolution, the thesis's future work): deep inside a thick medium the
/// light is smooth over a mean free path, and a tile's 512 voxels hold one value of the source
/// anyway (scatter's `band` makes them so beyond it). A coarse leaf is swept as one cube of
/// side 8 voxels: the light entering through its upwind faces (the neighbours' downwind faces'
/// means, each face by its share |ω_a|/|ω|₁ of the flow), carried over the cube's mean chord
/// 8/|ω|₁ voxels, leaves through its downwind faces as one value and gives the cell its mean,
/// conserving what enters, is absorbed and leaves (see sweep). Only the transport sweeps take
/// coarse leaves (the scatter stage); the optical-depth sweeps refuse them.
/// The chords of a coarse cell (a cube of 8 voxels a side) along a direction: from exit points
/// on a grid over its downwind faces back to the upwind face each entered by, with the share of
/// the light leaving there (each face's |ω_a|/|ω|₁, evenly over it). Their mean is 8/|ω|₁ voxels.
struct CubeChords
{
    static constexpr int kSide = 4; ///< exit points a face, a side
    explicit CubeChords(const openvdb::Vec3d& omega);
    struct Chord
    {
        double length, weight; ///< voxels; the share of the light leaving (all sum to 1)
        int exit, entry; ///< faces by their axis
    };
    std::vector<Chord> chords;
    double share[3] = {0.0, 0.0, 0.0}; ///< of the light leaving through each downwind face
    double mean = 0.0; ///< voxels
};

/// A CubeChords per direction.
std::vector<CubeChords> cubeChords(const std::vector<openvdb::Vec3d>& directions);

/// A coarse cell's step weights for one σt (1/world unit) along one direction's chords: the
/// light leaving through face a is Σ_e out[a][e]·in_e + outJ[a]·J, the cell's mean
/// Σ_e meanIn[e]·in_e + meanJ·J (in_e: the light entering through upwind face e; lengths in
/// world units); kept for the next cell of the same σt.
struct CoarseWeights
{
    double sigma = -1.0;
    const CubeChords* cube = nullptr;
    double out[3][3] = {}, outJ[3] = {}, meanIn[3] = {}, meanJ = 0.0;
};
const CoarseWeights& coarseWeights(double sigma, double voxelSize, const CubeChords& cube, CoarseWeights& cache);

class SweepLattice
{
public:
    static constexpr int kLeafVoxels = 512, kPaddedVoxels = 1000;
    /// Voxels of a leaf's three downwind faces (64 each) along an octant: what a sweep keeps of a leaf.
    static constexpr int kFaceVoxels = 192;
    /// At most this many directions of one octant sweep a leaf in turn (sweep), keeping
    /// kFaceVoxels values per leaf and direction: the fastest batch measured, and the smallest
    /// (docs/accuracy-notes.md, "Behind the code: SweepLattice").
    static constexpr std::size_t kSweepBatch = 2;
    /// The signed distance is held where a leaf's padded block comes within this many voxels of
    /// the surface, and is not wholly at a narrow-band level set's interior value (−3 voxels for
    /// vxf's and Houdini's half-width of 3: nothing closer is known there); elsewhere
    /// paddedDistance reads −kDistanceHeld (a sweep's steps there are whole either way; the light
    /// stage marches a point light's voxels within 3 of the surface).
    static constexpr float kDistanceHeld = 4.0f;

    /// What a lattice holds besides what a sweep reads: σt and σs per voxel, for the diffusion
    /// correction and the passes' sources (the scatter stage), or not (the light stage's sweeps:
    /// 24 bytes a voxel saved, 108 MB for the bunny at dim 256).
    enum class Coefficients { PerVoxel, SweepOnly };
    /// What the lattice makes of @a topology's active tiles: their voxels (Voxelized), or each
    /// 8³ block of a tile lying more than half a voxel inside the surface and at most
    /// maxCellDepth mean free paths across one coarse cell (Coarse; a block the density holds
    /// as voxels takes their means).
    enum class Tiles { Voxelized, Coarse };
    /// The coarse cells' largest optical size σt·8dx by default: cells of 4 mean free paths
    /// stalled the diffusion-accelerated solve (the thick bunny at dim 128: rate 0.97 after 40
    /// sweeps, its correction not the cells' transport), cells of 2 left the centre of a sphere
    /// of albedo 0.99 12% dark, cells of 1 put the bunny's image at dim 512 within 0.6% of full
    /// resolution (docs/accuracy-notes.md (ah)).
    static constexpr double kMaxCellDepth = 1.5;
    /// Whether the 8³ block at @a origin is thin enough to be one coarse cell: at most
    /// @a maxCellDepth mean free paths across (σt at its centre, the thickest channel).
    static bool thinEnoughForCell(Medium::Sampler& sampler, const openvdb::Coord& origin, double maxCellDepth = kMaxCellDepth);
    /// The lattice over @a medium's active density and @a topology's active values.
    SweepLattice(const Medium& medium, const openvdb::Vec3SGrid& topology, Coefficients coefficients = Coefficients::PerVoxel,
        Tiles tiles = Tiles::Voxelized, double maxCellDepth = kMaxCellDepth);
    SweepLattice(const Medium& medium, const openvdb::MaskTree& topology, Coefficients coefficients = Coefficients::PerVoxel,
        Tiles tiles = Tiles::Voxelized, double maxCellDepth = kMaxCellDepth);

    /// Leaves, fine ones (512 voxels) first, then coarse ones (one cell of 8³ voxels).
    std::size_t leafCount() const { return mOrigins.size(); }
    std::size_t fineLeafCount() const { return mFineLeaves; }
    bool coarse(std::size_t leaf) const { return leaf >= mFineLeaves; }
    /// Whether leaf @a leaf's padded block lies more than half a voxel inside the surface (or
    /// there is none): no voxel centre of it within half a voxel of the surface.
    bool deep(std::size_t leaf) const { return mDeep[leaf] != 0; }
    /// Whether leaf @a leaf holds its padded block of signed distances (kDistanceHeld).
    bool holdsDistance(std::size_t leaf) const { return distanceBlock(leaf) != nullptr; }
    /// Values of a per-voxel array: 512 a fine leaf, one a coarse leaf.
    std::size_t voxelCount() const { return mFineLeaves * kLeafVoxels + (mOrigins.size() - mFineLeaves); }
    /// Where leaf @a leaf's values start in a per-voxel array.
    std::size_t voxelStart(std::size_t leaf) const
    {
        return leaf < mFineLeaves ? leaf * kLeafVoxels : mFineLeaves * kLeafVoxels + (leaf - mFineLeaves);
    }
    /// The leaf holding per-voxel index @a voxel.
    std::size_t leafOf(std::size_t voxel) const
    {
        const std::size_t fine = mFineLeaves * kLeafVoxels;
        return voxel < fine ? voxel / kLeafVoxels : mFineLeaves + (voxel - fine);
    }
    /// The voxels per-voxel index @a voxel stands for: 1, or 512 for a coarse cell (the weight
    /// of its value in a sum over the medium).
    double voxelsAt(std::size_t voxel) const { return voxel < mFineLeaves * kLeafVoxels ? 1.0 : double(kLeafVoxels); }
    double voxelSize() const { return mVoxelSize; }
    const openvdb::Coord& origin(std::size_t leaf) const { return mOrigins[leaf]; }

    /// The bytes the lattice holds (its arrays' capacities, the leaf map's nodes estimated).
    std::size_t bytes() const;
    /// Whether σt is held grey (one float a voxel: every voxel's σt the same in each channel).
    bool greySigmaT() const { return !mSigmaTGrey.empty() || mSigmaT.empty(); }

    static int localIndex(int x, int y, int z) { return (x << 6) | (y << 3) | z; }
    static int paddedIndex(int x, int y, int z) { return (x + 1) * 100 + (y + 1) * 10 + (z + 1); }

    /// @a x with non-finite channels 0 and, with @a nonNegative, negative ones too: a voxel's
    /// coefficient as the lattice keeps it.
    static openvdb::Vec3d finiteCoefficient(openvdb::Vec3d x, bool nonNegative)
    {
        for (int ch = 0; ch < 3; ++ch) {
            if (!std::isfinite(x[ch]) || (nonNegative && x[ch] < 0.0)) x[ch] = 0.0;
        }
        return x;
    }
    /// A coefficient per voxel, read as an array (operator[] by per-voxel index): held per voxel
    /// (the medium's `sigma_a`/`sigma_s` grids), or made from the voxel's density and the
    /// material's coefficient as the medium's sampler makes it (4 bytes a voxel for σt and σs
    /// together, not 24), non-finite values 0 and, for σt, negative ones too.
    class Coefficient
    {
    public:
        openvdb::Vec3f operator[](std::size_t v) const
        {
            if (mValues) return (*mValues)[v];
            return openvdb::Vec3f(finiteCoefficient(mPerDensity * double((*mDensity)[v]), mNonNegative));
        }
        std::size_t size() const { return mValues ? mValues->size() : mDensity->size(); }
        bool empty() const { return size() == 0; }

    private:
        friend class SweepLattice;
        const std::vector<openvdb::Vec3f>* mValues = nullptr;
        const std::vector<float>* mDensity = nullptr;
        openvdb::Vec3d mPerDensity{0.0};
        bool mNonNegative = false;
    };
    /// σt per voxel, the voxel's own (volume-fraction weighted; 1/world unit); empty with
    /// Coefficients::SweepOnly.
    Coefficient sigmaT() const;
    /// Free sigmaT() where it is held per voxel (empty afterwards): only the diffusion
    /// correction's matrices read it, and a solve at dim 256 needs its 54 MB back (the sweeps
    /// read σt inside the surface, padded). Made from the density, it stays (σs needs that).
    void releaseSigmaT() { std::vector<openvdb::Vec3f>().swap(mSigmaTVoxel); }
    /// σs per voxel, the voxel's own (1/world unit); empty with Coefficients::SweepOnly.
    Coefficient sigmaS() const;
    /// The per-voxel index of local voxel (x, y, z) of leaf @a leaf, coordinates −8…15 reaching
    /// into the neighbouring leaves; −1 where there is no leaf.
    std::int64_t voxelIndex(std::size_t leaf, int x, int y, int z) const
    {
        const int dx = x < 0 ? -1 : (x > 7 ? 1 : 0), dy = y < 0 ? -1 : (y > 7 ? 1 : 0), dz = z < 0 ? -1 : (z > 7 ? 1 : 0);
        const int n = neighbour(leaf, dx, dy, dz);
        if (n < 0) return -1;
        return coarse(std::size_t(n)) ? std::int64_t(voxelStart(std::size_t(n)))
                                      : std::int64_t(n) * kLeafVoxels + localIndex(x - 8 * dx, y - 8 * dy, z - 8 * dz);
    }

    /// @a grid's values at the lattice's voxels (per voxel; tiles and inactive values as the
    /// grid holds them at each voxel, only where @a grid is active, 0 elsewhere).
    std::vector<openvdb::Vec3f> read(const openvdb::Vec3SGrid& grid) const;
    /// A grid's values at the lattice's voxels as read() gives them, without a per-voxel copy
    /// (a pointer to the grid's leaf, or its tile's value, per lattice leaf: 12 bytes a voxel
    /// saved for each grid a solve reads as it is). @a grid must outlive it.
    class GridView
    {
    public:
        GridView(const SweepLattice& lattice, const openvdb::Vec3SGrid& grid);
        /// The value at per-voxel index @a v (0 where the grid is not active; a coarse cell's
        /// the mean over its voxels).
        openvdb::Vec3f operator[](std::size_t v) const
        {
            if (v >= mFineVoxels) return mTiles[mFineLeaves + (v - mFineVoxels)];
            const std::size_t n = v / kLeafVoxels;
            const auto i = openvdb::Index(v % kLeafVoxels);
            if (const openvdb::Vec3STree::LeafNodeType* leaf = mLeaves[n])
                return leaf->isValueOn(i) ? leaf->getValue(i) : openvdb::Vec3f(0.0f);
            return mTiles[n];
        }

    private:
        std::vector<const openvdb::Vec3STree::LeafNodeType*> mLeaves; ///< per fine lattice leaf, or null
        /// per lattice leaf without a grid leaf: its active tile's value, or 0; a coarse leaf's mean
        std::vector<openvdb::Vec3f> mTiles;
        std::size_t mFineLeaves = 0, mFineVoxels = 0;
    };

    /// A Vec3f grid on @a topology's active topology and transform holding @a values (per
    /// voxel): its voxels their own value, an active tile the mean of its voxels. Non-finite
    /// values are written as 0.
    openvdb::Vec3SGrid::Ptr write(const std::vector<openvdb::Vec3f>& values, const openvdb::Vec3SGrid& topology) const;
    /// The per-voxel index of each of leaf @a leaf's padded voxels (kPaddedVoxels, in
    /// paddedIndex order) into @a index; −1 where no leaf is.
    void paddedVoxels(std::size_t leaf, std::int64_t* index) const;
    /// A source J as a sweep reads it, inside the surface (J/f): padded (a lattice without coarse
    /// leaves only: each leaf's block with
    /// its neighbours' values, read as it is by every direction: 23.4 bytes a voxel), or per
    /// voxel (12 bytes a voxel, a leaf's block gathered through its padded index when the sweep
    /// visits it: free where the sweep makes a block per direction anyway, the first moment's
    /// J·RestPhase, and 3-5% of the kernel's time where it would read the padded block as it is).
    struct SweepSource
    {
        enum class Layout { Padded, PerVoxel };
        ScratchArray<openvdb::Vec3f> values;
        Layout layout = Layout::Padded;
    };
    /// The source of @a source (per voxel, the voxels' own values), padded.
    /// (By value: a caller done with @a source moves it in, and its memory goes on return.)
    SweepSource sweepSource(std::vector<openvdb::Vec3f> source) const;
    /// The same from @a sourceAt(v), the source at each voxel (per-voxel index), made in
    /// @a layout directly: no per-voxel array of J beside it.
    SweepSource sweepSource(
        const std::function<openvdb::Vec3f(std::size_t)>& sourceAt, SweepSource::Layout layout = SweepSource::Layout::Padded) const;
    /// The same made in @a reuse's memory when it is of the size needed (an iteration's source
    /// made again in the last one's: fresh memory costs its page faults every time, 1 GB and 4 s
    /// of one thread an iteration for the bunny at dim 1024 on a 2-core virtual machine).
    SweepSource sweepSource(
        const std::function<openvdb::Vec3f(std::size_t)>& sourceAt, SweepSource::Layout layout, SweepSource reuse) const;

    /// One transport sweep per direction: the radiance ψ(x, ω) of dψ/ds = −σt ψ + J with no
    /// light entering the lattice from outside, and @a fluence += Σ_i @a weight·ψ(x, ω_i) (per
    /// voxel, at the voxels' centres). @a source: from sweepSource. Upwind order leaf by leaf
    /// (see SweepPass.h). With @a skinFluence (skinCount() values), also the fluence of each
    /// skin voxel on the surface (see putSkin).
    ///
    /// With @a moment, the source is anisotropic by the rest of the phase (Phase.h) and the
    /// sweep adds up the fluence's first moment too: direction i sweeps the source
    /// J·RestPhase(a, ω_i, β·ω_i) (a per voxel, the source's mean direction of travel; β its
    /// direction set's correction), and flux += Σ_i weight·grey(ψ_i)·ω_i (per
    /// voxel). ω_i and a are in world space (worldDirections: @a directions carried to it).
    struct FirstMoment
    {
        RestPhase rest; ///< the rest's moments
        /// a, per voxel (read padded a leaf at a time as the sweep visits it: 24 bytes a voxel
        /// less than held padded)
        const std::vector<openvdb::Vec3f>* sourceAnisotropy = nullptr;
        /// β·ω's cubic form, one per direction (QuadratureCorrection for worldDirections), or
        /// empty: none.
        std::vector<QuadratureCorrection> corrections;
        std::vector<openvdb::Vec3d> worldDirections; ///< one per sweep direction, unit
        std::vector<openvdb::Vec3f>* flux = nullptr; ///< per voxel, added to
    };
    void sweep(const SweepSource& source, const std::vector<openvdb::Vec3d>& directions, double weight,
        std::vector<openvdb::Vec3f>& fluence, std::vector<openvdb::Vec3f>* skinFluence = nullptr, Interrupter* interrupter = nullptr,
        const FirstMoment* moment = nullptr) const;

    /// Optical depth τ = ∫ σt ds (per channel, world σt × world length) of light crossing the
    /// lattice, at every voxel centre (per voxel), by one upwind sweep: a voxel's τ is the
    /// bilinear blend of its four upwind voxels' at the short characteristic's crossing of the
    /// previous layer of centres (as in sweep), plus the step's own from there (its part inside
    /// the surface, σt the mean of the step's ends). Along a planar front in a uniform medium τ is
    /// linear, so the blend is exact there; blending the transmittance instead (convex in depth)
    /// brightens every step. Where light enters between upwind voxels on either side of the
    /// surface, their depth is continued through it (see the implementation). O(voxels), not a
    /// march per voxel; results do not depend on the thread count.
    ///
    /// Light reaching the lattice's upwind side from a voxel of no leaf may have crossed medium
    /// before, beyond a gap of vacuum (the bunny's head shadowing its chest): @a entering(ijk,
    /// swept) gives the optical depth already on the path at such a voxel (e.g. a march from it
    /// toward the light, or the depth @a swept holds where the path left the medium upwind);
    /// null: τ = 0 there, the lattice alone casts shadows. Parallel light travelling along
    /// @a direction (unit, index space).
    ///
    /// Beyond an optical depth of @a opaque light counts as blocked (the marches' cutoff): a leaf
    /// holding no surface whose upwind ghosts all lie beyond it (every channel) is not swept but
    /// takes the least of their depths at every voxel, which its own lie above (σt ≥ 0, and only
    /// the continuation through a surface lowers a depth). Its light is 0 either way; a voxel
    /// downwind blending them with lit depths (a shadow's edge) reads the least, a change of its
    /// transmittance of the order of the cutoff's own in a medium (under 3 × 10^-4 on a sphere at
    /// 10^-4, 4 × 10^-8 within a sphere with a surface), more in the vacuum voxels of the lattice
    /// in the shadow behind a surface (0.11 there), whose light no medium reads.
    /// The thick bunny's light at dim 1024: 238 → 187 s.
    class SweptSoFar;
    class Depths;
    using EnteringDepth = std::function<openvdb::Vec3f(const openvdb::Coord&, const SweptSoFar&)>;
    void opticalDepthAlong(const openvdb::Vec3d& direction, Depths& tau, const EnteringDepth& entering = {},
        float opaque = std::numeric_limits<float>::infinity()) const;

    /// Optical depth τ from a point light at @a point (index space) to every voxel centre (per
    /// voxel), by one upwind sweep per octant around it (octant by octant, bit a set for voxels
    /// below the point along axis a): a voxel's τ is the blend of its four upwind voxels' at the
    /// crossing of its own short characteristic (the ray from the point, a direction per voxel)
    /// with the previous layer of centres, plus the step's own, as in opticalDepthAlong (the
    /// surface's kink continued the same way). The result does not depend on the thread count.
    ///
    /// Each voxel is first offered to @a marched(ijk, signedDistance, mustMarch, swept, depth):
    /// true with @a depth τ from the point to the voxel's centre takes that instead (e.g. a march,
    /// for voxels near the surface, where a blend of upwind depths smears the light's steep
    /// fall). With mustMarch the sweep has nothing to blend and @a marched must give the depth:
    /// voxels within a voxel of the point (no upwind layer), and voxels with an upwind voxel in
    /// no leaf (light across vacuum) or across one of the point's planes in an octant not swept
    /// yet. @a swept reads what is final so far (SweptSoFar), e.g. for a march that hands off.
    /// @a state (per voxel): kMarched where @a marched gave the depth, kBlended where the sweep
    /// did (SweptSoFar::sample reads only marched ones where asked).
    ///
    /// Beyond an optical depth of @a opaque light counts as blocked, as in opticalDepthAlong: a
    /// uniform leaf (deep inside, one σt) whose upwind ghosts and itself lie in one octant and
    /// whose ghosts all hold depths whose bound darkLeafDepth puts beyond it is not swept (nor
    /// offered to @a marched: a voxel near the surface there lies where light has crossed that
    /// much medium) but takes that bound, which every depth the sweep would give it lies above.
    /// Downwind of it, as in opticalDepthAlong, the light within a sphere with a surface is the
    /// same bits; in the vacuum voxels in the shadow behind it up to 0.17 lighter.
    using MarchedDepth = std::function<bool(
        const openvdb::Coord& ijk, float signedDistance, bool mustMarch, const SweptSoFar& swept, openvdb::Vec3f& depth)>;
    void opticalDepthFrom(const openvdb::Vec3d& point, Depths& tau, std::vector<std::uint8_t>& state, const MarchedDepth& marched,
        float opaque = std::numeric_limits<float>::infinity()) const;
    /// opticalDepthFrom's states of a voxel: not yet swept, blended from upwind, marched.
    static constexpr std::uint8_t kPending = 0, kBlended = 1, kMarched = 2;
    /// The octant around @a point voxel @a ijk lies in (bit a set: ijk[a] < point[a]).
    static int octantAround(const openvdb::Coord& ijk, const openvdb::Vec3d& point);

    /// The per-voxel index of voxel @a ijk, or −1 when no leaf of the lattice holds it.
    std::int64_t indexOf(const openvdb::Coord& ijk) const
    {
        const auto found = mLeafIndex.find(ijk & ~7);
        if (found == mLeafIndex.end()) return -1;
        const auto n = std::size_t(found->second);
        return coarse(n) ? std::int64_t(voxelStart(n)) : std::int64_t(n) * kLeafVoxels + localIndex(ijk[0] & 7, ijk[1] & 7, ijk[2] & 7);
    }

    /// @a values (per voxel) with each skin voxel's replaced by centre(voxel)·f: for a source made
    /// from a pass's fluence, whose skin voxels hold the light on the surface (putSkin), the
    /// value at the centre that sweepSource takes it for (@a centre: the source inside the
    /// surface at a voxel's centre, e.g. SourceField's; f its volume fraction).
    void skinAtCentres(std::vector<openvdb::Vec3f>& values, const std::function<openvdb::Vec3f(const openvdb::Coord&)>& centre) const;

    /// The surface's skin: voxels whose centre lies within half a voxel of it, either side
    /// (Medium::Sampler::skinPoint). The gathers give them the fluence at their nearest surface
    /// point, where the renderer and SourceField read them (the scattered light rises steeply
    /// beneath a surface, as 1 − E2(σt z)/2: half a voxel deep it is far above its value on the
    /// surface). A sweep carries each direction leaving the surface (ω·n > 0) on from the
    /// centre to the surface, ψ e^{−τ'} + S(1 − e^{−τ'}) over the depth d/(ω·n) (none for a
    /// centre outside), and drops those entering (no light comes from outside).
    std::size_t skinCount() const { return mSkin.size(); }
    /// Whether voxel @a voxel (per-voxel index) is a skin voxel.
    bool isSkin(std::size_t voxel) const { return skinIndexOf(voxel) >= 0; }
    /// @a fluence's (per voxel) skin voxels' values replaced by @a skinFluence plus @a shift at
    /// the voxel (e.g. a diffusion correction; null: none), in place.
    void putSkin(std::vector<openvdb::Vec3f>& fluence, const std::vector<openvdb::Vec3f>& skinFluence,
        const std::vector<openvdb::Vec3f>* shift = nullptr) const;

    /// The leaf at @a leaf's origin + 8·(dx, dy, dz), dx… ∈ {−1, 0, 1}, or −1 for none.
    int neighbour(std::size_t leaf, int dx, int dy, int dz) const
    {
        return mNeighbours[leaf * 27 + (dx + 1) * 9 + (dy + 1) * 3 + (dz + 1)];
    }

    /// Wavefront key of leaf @a leaf along @a octant's diagonal: a leaf's upwind neighbours
    /// have smaller keys, and a wavefront's leaves are swept once every smaller key's are.
    long long frontKey(std::size_t leaf, int octant) const
    {
        long long k = 0;
        for (int a = 0; a < 3; ++a) k += ((octant >> a) & 1 ? -1 : 1) * (long long)(mOrigins[leaf][a] >> 3);
        return k;
    }

private:
    /// The leaves of @a medium's density and @a topology (tiles voxelized, or coarse as @a tiles
    /// says), their neighbours and their upwind orders.
    void indexLeaves(const Medium& medium, const openvdb::MaskTree& topology, Tiles tiles, double maxCellDepth);
    /// The origins of the 8³ blocks of @a topology's active tiles that lie more than half a voxel
    /// inside @a medium's surface (all of them without one) and at most @a maxCellDepth mean
    /// free paths across: the coarse leaves.
    static std::vector<openvdb::Coord> coarseBlocks(const Medium& medium, const openvdb::MaskTree& topology, double maxCellDepth);
    /// σt inside the surface per voxel while readMedium reads it: one float a voxel (`grey`) or
    /// three (`rgb`), the other array empty.
    struct InsideSigma
    {
        InsideSigma(std::size_t voxels, bool greyKnown)
        {
            if (greyKnown) {
                grey = ScratchArray<float>(voxels);
            } else {
                rgb = ScratchArray<openvdb::Vec3f>(voxels);
            }
        }
        void set(std::size_t i, const openvdb::Vec3f& sigma)
        {
            if (grey.empty()) {
                rgb[i] = sigma;
            } else {
                grey[i] = sigma[0];
            }
        }
        openvdb::Vec3f at(std::size_t i) const { return grey.empty() ? rgb[i] : openvdb::Vec3f(grey[i]); }
        /// Held as one float a voxel when every voxel's σt is the same in each channel.
        void makeGreyIfItIs();
        ScratchArray<float> grey;
        ScratchArray<openvdb::Vec3f> rgb;
    };
    /// A coarse leaf's one cell: its σt (inside, the mean over its voxels), σs or density and
    /// distance, at its per-voxel index.
    void readCoarseCell(std::size_t leaf, Medium::Sampler& sampler, openvdb::FloatGrid::ConstAccessor& density, bool perVoxel,
        bool fromDensity, InsideSigma& inside, ScratchArray<float>& distance);
    /// Coarse leaf @a leaf of a transport sweep along @a directions[@a d] (@a chords, its
    /// cube's): the light entering it from what its upwind neighbours handed on (@a faces: the
    /// fine leaves' downwind faces, at their places @a facePlace; @a leaving: the coarse leaves'
    /// light, of this direction), its
    /// step (sweepCoarseCell) into @a fluence (and a moment's flux), and what it hands on into
    /// @a leaving.
    void sweepCoarseLeaf(std::size_t leaf, const std::vector<openvdb::Vec3d>& directions, std::size_t d, const CubeChords& chords,
        const openvdb::Vec3f* faces, const std::int32_t* facePlace, openvdb::Vec3f* leaving, const SweepSource& source, float weight,
        std::vector<openvdb::Vec3f>& fluence, const FirstMoment* moment, CoarseWeights& cache) const;
    /// One coarse leaf of a transport sweep: @a in the light entering it through each upwind
    /// face (by axis), @a j its source; the light leaving through each downwind face into
    /// @a out, @a weight times its mean added to @a phi (and the flux's).
    void sweepCoarseCell(std::size_t leaf, const CubeChords& cube, const openvdb::Vec3f (&in)[3], const openvdb::Vec3f& j, float weight,
        openvdb::Vec3f& phi, openvdb::Vec3f* flux, const openvdb::Vec3f& worldOmega, CoarseWeights& cache, openvdb::Vec3f* out) const;
    /// A lower bound of every depth opticalDepthFrom around @a point would give leaf @a leaf in
    /// @a octant, from the least of its upwind ghosts' @a tau, when the leaf may be skipped as
    /// dark (see there); −1 when it may not (not uniform, a ghost in no leaf or across one of the
    /// point's planes).
    float darkLeafDepth(std::size_t leaf, int octant, const openvdb::Vec3d& point, const Depths& tau) const;
    /// Throws unless every leaf is fine (the optical-depth sweeps, whose voxels the light stage writes one by one).
    void requireFine(const char* what) const;
    /// σt (padded), the surface's distance, 1/f and skin, and with @a perVoxel σt and σs per voxel.
    void readMedium(const Medium& medium, bool perVoxel);
    /// From the per-voxel σt inside (@a inside), signed distance and 1/f (@a interior; both
    /// empty without a surface), each fine leaf classified on its padded blocks (mDeep,
    /// mUniform) and then only what its sweeps read held, padded: σt as one value for a uniform
    /// leaf and @a coarseSigmaT's one a coarse leaf (mSigmaTStart), 1/f for the leaves that are
    /// not deep (mShallowStart), the distance for those within kDistanceHeld of the surface and
    /// not wholly at @a interiorDistance (a narrow-band level set's interior value). No leaf's
    /// block is made before it is known to be kept (the bunny at dim 1024: 3.4 GB of blocks had
    /// been made whole and compacted after, 10 s of one thread).
    void holdPadded(const InsideSigma& inside, const ScratchArray<float>& distance, const ScratchArray<float>& interior,
        const std::vector<openvdb::Vec3f>& coarseSigmaT, float interiorDistance);
    /// A Coefficient of @a held values, or of the density times @a perDensity (@a nonNegative:
    /// negative values read 0).
    Coefficient coefficient(const std::vector<openvdb::Vec3f>& held, const openvdb::Vec3d& perDensity, bool nonNegative) const;

    /// A leaf's voxel as a sweep visits it: its index in the padded block and in the leaf.
    struct UpwindVoxel
    {
        std::int16_t padded, local;
    };
    /// The 512 voxels of a leaf in upwind order along @a octant, each axis from its upwind side,
    /// layer by layer across axis @a major (0…2) and in each layer the next axis, then the third:
    /// every voxel after the voxels it reads. With @a major the direction's dominant axis, whose
    /// previous layer a short characteristic reads, the 64 voxels of a layer depend on none of
    /// each other, and the processor overlaps them (in x-y-z order for every direction, a third
    /// of the directions waited on the voxel just before).
    static const std::array<UpwindVoxel, kLeafVoxels>& upwindVoxels(int octant, int major);

    /// The leaves in upwind order along @a omega's octant (a wavefront's leaves in parallel),
    /// each with a padded buffer (kPaddedVoxels, one per thread) whose upwind ghost cells hold
    /// @a values (per voxel; where no leaf is, @a outside(ijk) if given, else 0): visit(leaf,
    /// buffer, voxels) once per leaf, which takes its voxels in the order of @a voxels
    /// (upwindVoxels) and writes each one's own value to the buffer and to @a values. One call a
    /// leaf, not a voxel: what is the same over a leaf is looked at once. visit's fourth argument
    /// is the least of the ghosts' values (every channel).
    template <typename Visit>
    void inUpwindOrder(const openvdb::Vec3d& omega, const Depths& values, const Visit& visit, const EnteringDepth& outside = {}) const;
    /// visit(leaf) for the leaves in upwind order along @a octant, a wavefront's in parallel.
    template <typename Visit>
    void leavesInUpwindOrder(int octant, const Visit& visit) const;
    /// τ at voxel @a p (padded index in leaf @a leaf) from its four upwind voxels' @a tauUpwind
    /// (bilinear @a weight at padded @a offset, the step @a length voxels along unit @a omega):
    /// the step of opticalDepthAlong and opticalDepthFrom.
    openvdb::Vec3f depthStep(std::size_t leaf, int p, const openvdb::Vec3d& omega, const float (&weight)[4], const int (&offset)[4],
        double length, const openvdb::Vec3f (&tauUpwind)[4]) const;
    /// One leaf of a transport sweep along @a omega (sweep): its voxels a row at a time in
    /// upwind order (forRows in SweepTransport.cc), the upwind ghosts already in @a buffer
    /// (padded), the source @a j (padded, the leaf's);
    /// each voxel's ψ into @a buffer, @a weight·ψ added to @a phi (the leaf's, per voxel) and, with
    /// @a flux, @a weight·grey(ψ)·@a worldOmega to it; with @a skinFluence, the skin's too.
    /// @a st: the leaf's padded σt (mSigmaTGrey's or mSigmaT's: float or Vec3f).
    template <typename Sigma>
    void sweepLeaf(std::size_t leaf, const Sigma* st, const openvdb::Vec3d& omega, const openvdb::Vec3f* j, openvdb::Vec3f* buffer,
        float weight, openvdb::Vec3f* phi, openvdb::Vec3f* flux, const openvdb::Vec3f& worldOmega,
        std::vector<openvdb::Vec3f>* skinFluence) const;
    /// σt at padded index @a p of leaf @a leaf (a uniform leaf's one value for every @a p).
    openvdb::Vec3f paddedSigmaT(std::size_t leaf, int p) const
    {
        const std::size_t q = mSigmaTStart[leaf] + (mUniform[leaf] ? 0 : std::size_t(p));
        return mSigmaTGrey.empty() ? mSigmaT[q] : openvdb::Vec3f(mSigmaTGrey[q]);
    }
    /// Per-voxel index @a voxel's place in the arrays held only for leaves that are not deep
    /// (mInterior, mSkinIndex), or kNone in a deep leaf.
    static constexpr std::size_t kNone = ~std::size_t(0);
    std::size_t shallowIndex(std::size_t voxel) const
    {
        if (mShallowStart.empty() || voxel >= mFineLeaves * kLeafVoxels) return kNone; // (a coarse cell is deep)
        const std::size_t start = mShallowStart[voxel / kLeafVoxels];
        return start == kNone ? kNone : start + voxel % kLeafVoxels;
    }
    /// 1/f at voxel @a voxel: 1 without a surface and in a deep leaf (every voxel whole).
    float interiorOf(std::size_t voxel) const
    {
        const std::size_t i = shallowIndex(voxel);
        return i == kNone ? 1.0f : mInterior[i];
    }
    /// Voxel @a voxel's entry in mSkin, or −1.
    std::int32_t skinIndexOf(std::size_t voxel) const
    {
        const std::size_t i = shallowIndex(voxel);
        return i == kNone || mSkinIndex.empty() ? -1 : mSkinIndex[i];
    }
    /// Leaf @a leaf's padded block of signed distances, or null where none is held (no
    /// surface, or a leaf lying kDistanceHeld voxels or more inside it).
    const float* distanceBlock(std::size_t leaf) const
    {
        return mDistanceStart.empty() || mDistanceStart[leaf] == kNone ? nullptr : &mDistance[mDistanceStart[leaf]];
    }
    /// The signed distance at padded voxel @a p of leaf @a leaf: −1 without a surface,
    /// −kDistanceHeld where the leaf holds none (deeper than that).
    float paddedDistance(std::size_t leaf, int p) const
    {
        if (mDistance.empty()) return -1.0f;
        const float* block = distanceBlock(leaf);
        return block ? block[p] : -kDistanceHeld;
    }

    double mVoxelSize = 1.0;
    std::vector<openvdb::Coord> mOrigins; ///< fine leaves first, then coarse ones
    std::size_t mFineLeaves = 0;
    std::unordered_map<openvdb::Coord, std::int32_t, CoordHash> mLeafIndex; ///< leaf origin → n
    std::vector<std::int32_t> mNeighbours; ///< 27 per leaf
    /// Per octant (bit a set: direction negative along axis a), the leaves in upwind order,
    /// cut into wavefronts: leaves of one wavefront depend on none of each other.
    std::array<std::vector<std::int32_t>, 8> mOrder;
    std::array<std::vector<std::size_t>, 8> mWavefronts; ///< start of each wavefront in mOrder, then its end
    /// Per octant, each fine leaf's place among the downwind faces a transport sweep keeps
    /// (kFaceVoxels values a place): a leaf's upwind neighbours lie 1 to 3 wavefronts before
    /// it, so the places of the last four wavefronts' fine leaves are all a sweep holds, the
    /// wavefront at key k in places [(k mod 4)·w, (k mod 4 + 1)·w) with w its octant's widest
    /// wavefront (mFacePlaces: 4w). The banded bunny at dim 1024: 0.6 GB of faces, not 1.2.
    std::array<std::vector<std::int32_t>, 8> mFacePlace;
    std::array<std::size_t, 8> mFacePlaces{};
    /// σt padded, inside the surface (σt/f): one float a voxel where every voxel's σt is grey
    /// (the same in each channel: a medium of one mean free path, whatever its albedo), three
    /// otherwise; the other array empty.
    std::vector<openvdb::Vec3f> mSigmaT;
    std::vector<float> mSigmaTGrey;
    /// Per leaf, where its σt starts in mSigmaT or mSigmaTGrey: a block of kPaddedVoxels, or
    /// one value for a uniform or coarse leaf (its sweeps read that one: about half the thick bunny's
    /// leaves at dim 256, more as the interior grows).
    std::vector<std::size_t> mSigmaTStart;
    /// Padded, signed distance to the surface (voxels), per fine leaf from mDistanceStart
    /// (kNone: a leaf whose padded block lies kDistanceHeld or more inside, where a sweep's
    /// steps are whole and a reader takes −kDistanceHeld: at dim 1024 most of the bunny's
    /// leaves, 1.5 GB); empty without a surface (a volume object's medium: every voxel whole,
    /// f = 1, as if −1 everywhere).
    std::vector<float> mDistance;
    std::vector<std::size_t> mDistanceStart;
    std::vector<std::uint8_t> mDeep; ///< per leaf: its padded block more than half a voxel inside the surface (a coarse leaf: 1)
    std::vector<std::uint8_t> mUniform; ///< per leaf: deep, and one σt over its padded block (sweep's short path)
    /// Per leaf with a surface, where its 512 voxels start in mInterior and mSkinIndex, or kNone
    /// for a deep leaf (f = 1 and no skin there); empty without a surface.
    std::vector<std::size_t> mShallowStart;
    std::vector<float> mInterior; ///< per voxel of the leaves that are not deep, 1/f; empty without a surface (f = 1)
    /// σt and σs per voxel (Coefficients::PerVoxel): held (the medium's σa/σs grids), or the
    /// voxel's density with the material's coefficients (the other arrays empty).
    std::vector<openvdb::Vec3f> mSigmaTVoxel, mSigmaS;
    std::vector<float> mDensityVoxel;
    openvdb::Vec3d mMaterialSigmaT{0.0}, mMaterialSigmaS{0.0};
    struct Skin
    {
        std::uint32_t voxel; ///< per-voxel index
        openvdb::Vec3f normal; ///< outward unit normal
        float depth; ///< world units from the centre to the surface (0 for a centre outside)
    };
    std::vector<Skin> mSkin;
    std::vector<std::int32_t> mSkinIndex; ///< per voxel of the leaves that are not deep, its entry in mSkin or −1
};

/// An optical depth per lattice voxel (opticalDepthAlong, opticalDepthFrom): one float where
/// the lattice's σt is grey (then every depth is: a march's too, of the same σt), three
/// otherwise. The bunny at dim 1024: 0.9 GB a sweep, not 2.6.
class SweepLattice::Depths
{
public:
    /// A depth of 0 at every voxel of @a lattice, grey as its σt (written on every thread: a
    /// sweep's 0.9 GB at dim 1024, made again for every direction).
    void assignZero(const SweepLattice& lattice)
    {
        const bool grey = lattice.greySigmaT();
        if (grey != this->grey() || size() != lattice.voxelCount()) {
            mGrey = ScratchArray<float>(grey ? lattice.voxelCount() : 0);
            mColour = ScratchArray<openvdb::Vec3f>(grey ? 0 : lattice.voxelCount());
        }
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, size()), [&](const tbb::blocked_range<std::size_t>& r) {
            if (grey) {
                std::fill(mGrey.data() + r.begin(), mGrey.data() + r.end(), 0.0f);
            } else {
                std::fill(mColour.data() + r.begin(), mColour.data() + r.end(), openvdb::Vec3f(0.0f));
            }
        });
    }
    openvdb::Vec3f operator[](std::size_t i) const { return mColour.empty() ? openvdb::Vec3f(mGrey[i]) : mColour[i]; }
    void set(std::size_t i, const openvdb::Vec3f& tau)
    {
        if (mColour.empty()) {
            mGrey[i] = tau[0];
        } else {
            mColour[i] = tau;
        }
    }
    std::size_t size() const { return mColour.empty() ? mGrey.size() : mColour.size(); }
    bool grey() const { return mColour.empty(); }
    bool operator==(const Depths& other) const
    {
        return grey() == other.grey() && size() == other.size() &&
            (grey() ? std::equal(mGrey.data(), mGrey.data() + size(), other.mGrey.data())
                    : std::equal(mColour.data(), mColour.data() + size(), other.mColour.data()));
    }

private:
    ScratchArray<float> mGrey;
    ScratchArray<openvdb::Vec3f> mColour;
};

/// What a sweep in progress has finished, as an EnteringDepth or MarchedDepth sees it while a
/// leaf is swept: the values of the leaves of earlier wavefronts (and, around a point, of the
/// octants swept before), final whatever the thread count (later ones, the current
/// wavefront's included, may be half done and are never read).
class SweepLattice::SweptSoFar
{
public:
    SweptSoFar(const SweepLattice& lattice, const Depths& values, int octant, long long key)
        : mLattice(lattice)
        , mValues(values)
        , mOctant(octant)
        , mKey(key)
    {
    }
    /// A sweep around @a point (opticalDepthFrom) in @a octant while it sweeps @a leaf (at
    /// wavefront @a key), the voxels' @a state: the leaf's own voxels swept so far are final too
    /// (one thread writes them, in an order that takes every voxel after those upwind of it).
    SweptSoFar(const SweepLattice& lattice, const Depths& values, int octant, std::size_t leaf, long long key, const openvdb::Vec3d& point,
        const std::vector<std::uint8_t>* state)
        : mLattice(lattice)
        , mValues(values)
        , mOctant(octant)
        , mKey(key)
        , mAroundPoint(true)
        , mLeaf(leaf)
        , mPoint(point)
        , mState(state)
    {
    }
    /// A finished sweep's @a values (per voxel): every leaf; with @a state, opticalDepthFrom's.
    SweptSoFar(const SweepLattice& lattice, const Depths& values, const std::vector<std::uint8_t>* state = nullptr)
        : mLattice(lattice)
        , mValues(values)
        , mOctant(0)
        , mKey(std::numeric_limits<long long>::max())
        , mState(state)
    {
    }

    /// Trilinear interpolation of the swept values at index-space point @a ijk (voxel centres at
    /// integer coordinates); false (@a value untouched) where one of the eight voxels it reads
    /// lies in no leaf or is not final yet, or with @a marchedOnly, was neither marched nor 0
    /// (opticalDepthFrom's blends of zeros are exactly 0), or where the eight values spread over
    /// more than @a maxSpread (any channel).
    bool sample(const openvdb::Vec3d& ijk, openvdb::Vec3f& value, bool marchedOnly = false,
        float maxSpread = std::numeric_limits<float>::infinity()) const
    {
        const openvdb::Coord base = openvdb::Coord::floor(ijk);
        // The eight in one leaf (base not on its upper face along any axis): one leaf lookup.
        const bool oneLeaf = (base[0] & 7) != 7 && (base[1] & 7) != 7 && (base[2] & 7) != 7;
        const std::int64_t first = oneLeaf ? mLattice.indexOf(base) : -1;
        if (oneLeaf && first < 0) return false;
        openvdb::Vec3f corner[2][2][2];
        for (int i = 0; i < 2; ++i) {
            for (int j = 0; j < 2; ++j) {
                for (int k = 0; k < 2; ++k) {
                    const openvdb::Coord c = base.offsetBy(i, j, k);
                    const std::int64_t at = oneLeaf ? first + localIndex(i, j, k) : mLattice.indexOf(c);
                    if (at < 0) return false;
                    const std::size_t leaf = std::size_t(at) / kLeafVoxels;
                    if (mAroundPoint && leaf == mLeaf) {
                        if ((*mState)[std::size_t(at)] == kPending) return false;
                    } else {
                        const int octant = mAroundPoint ? octantAround(c, mPoint) : mOctant;
                        if (octant > mOctant) return false;
                        if (octant == mOctant && mLattice.frontKey(leaf, mOctant) >= mKey) return false;
                    }
                    corner[i][j][k] = mValues[std::size_t(at)];
                    if (marchedOnly && (!mState || (*mState)[std::size_t(at)] != kMarched) && corner[i][j][k] != openvdb::Vec3f(0.0f)) {
                        return false;
                    }
                }
            }
        }
        if (maxSpread < std::numeric_limits<float>::infinity()) {
            openvdb::Vec3f lo = corner[0][0][0], hi = corner[0][0][0];
            for (int c = 1; c < 8; ++c) {
                lo = openvdb::math::minComponent(lo, corner[c >> 2][(c >> 1) & 1][c & 1]);
                hi = openvdb::math::maxComponent(hi, corner[c >> 2][(c >> 1) & 1][c & 1]);
            }
            if (std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]}) > maxSpread) return false;
        }
        value = openvdb::tools::BoxSampler::trilinearInterpolation(corner, ijk - base.asVec3d());
        return true;
    }

private:
    const SweepLattice& mLattice;
    const Depths& mValues;
    int mOctant;
    long long mKey;
    bool mAroundPoint = false;
    std::size_t mLeaf = 0;
    openvdb::Vec3d mPoint{0.0};
    const std::vector<std::uint8_t>* mState = nullptr;
};

} // namespace vxf::detail
