// GCP's local reconstruction one brick at a time, from end to end: each brick of a grid, read
// with a halo, gives the piece of the mesh that it owns (contact points, vertices, subdivision and
// projection all computed from the brick's block), with global vertex keys, so that pieces made
// anywhere (threads, processes, machines) join into one mesh, bit for bit the same whatever the
// bricks.
//
// Ownership: a brick owns the grid edges whose low sample lies in its range [own_first,
// own_end) on each axis, and the triangles of those edges' dual polygons (local_reconstruction.h),
// each subdivided. Every value a piece's vertex depends on (the cells' contact points and their
// samples' certified stars, the gradients at the cells' corners, the contact points within the
// projection's radius, the triangles around the vertex for its normal) lies in the block, and is
// combined in an order fixed by global names: the result equals the whole grid's run (one brick).
// Carving runs vertex by vertex; its triangle rounds and the untangling (whole-mesh stages) are
// not part of it.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <vector>

#include "sdfcontour/band/band.h"
#include "sdfcontour/contact_points/contact_points.h"
#include "sdfcontour/contact_points/gradients.h"
#include "sdfcontour/contact_points/lattice_contact_points.h"
#include "sdfcontour/input/blocked_grid.h"
#include "sdfcontour/input/samples.h"
#include "sdfcontour/reconstruction/contact_projection.h"
#include "sdfcontour/reconstruction/local_reconstruction.h"
#include "sdfcontour/reconstruction/zero_set_refinement.h"

namespace sdfcontour {

namespace detail {
class LatticePointStore;
}

/// The bricks' side (cells) with which a callable's or a Dask grid's local reconstruction runs
/// when no brick size is given: memory bounded by a brick and its halo.
constexpr int kLocalBrick = 256;

/// The same for a grid already in memory (contour() on an array): one brick up to 512 samples
/// per axis. Each brick recomputes a halo of ~55 samples on its inner sides (kUntangleRing and the
/// band): bunny at 512^3 on 2 cores took 106 s in bricks of 256 and 61 s in one brick (the same
/// mesh), for a peak RSS of 3.58 GB instead of 2.98 GB. With edge fans, whose halo is a cell or
/// two, a grid in memory takes kLocalBrick too: bunny 512^3 (float32, truncated at 8 spacings,
/// lattice gradients on a band of 2) 26.6 s and 1.72 GB in one brick, 22.7 s and 0.48 GB in
/// bricks of 256, the same mesh (at 256^3, bricks of 128 were 1.25x slower than one).
constexpr int kLocalGridBrick = 512;

/// Rounds of undoing crossing moves. A piece's triangles depend on the triangles within
/// kCrossingReach grid edges of them per round (carving moves a vertex at most kMaxCarveMove
/// spacings, projection at most its max_move: triangles that start farther apart cannot meet),
/// so a brick computes the mesh of its edges and kUntangleRing more on each side.
constexpr int kUntangleRounds = 4;
constexpr int kSideRounds = 1;
constexpr double kMaxCarveMove = 0.5;
constexpr double kLongestSideMove = 0.5;
/// Vertices move at most 0.25 (projection) + kMaxCarveMove + kSideRounds * kLongestSideMove
/// spacings: triangles of grid edges this far apart cannot meet.
constexpr int kCrossingReach = 5;
/// A side round's move depends on the samples within a spacing of a triangle near the vertex.
constexpr int kSideReach = 4;
/// Rounds that move the quadrics' vertices of crossing triangles to their crossings' mean
/// (inside their cells: triangles of grid edges kCrossingReach apart cannot meet).
constexpr int kDualUntangleRounds = 2;
/// (The rounds: the dual mesh's, the side rounds and the undoing rounds, then one side round and
/// one undoing round for the samples whose sides the undoing lost.)
constexpr int kUntangleRing = 1 + kSideReach * (kSideRounds + 1) +
                              kCrossingReach * (kDualUntangleRounds + kUntangleRounds + 2);

/// Grid edges that splitting the sagging edges adds to a brick's ring: a split asks for its
/// ends' normals (their triangles), a new vertex's projection for its own.
constexpr int kSplitReach = 2;
/// Samples beyond a brick's reach whose contact points decide the thin parts' points.
constexpr int kThinPartReach = 2;

/// Contact points made before the bricks for the whole grid (GTCP's exact ones, or those of the
/// Delaunay or k-nearest gradients on the whole band): each brick takes those of the samples it
/// reads instead of making its own; the rest of the chain is the same.
struct GivenContactPoints {
  PointMatrix points, normals;  ///< k x 3: the points and their unit outward normals
  Eigen::VectorXd depths;       ///< k: |value| of each point's sample (the projection's weight)
  /// k: each point's sample, its global C-order index in the whole grid (a brick keeps the
  /// points in their order here, so every brick sums them alike).
  std::vector<std::uint64_t> samples;
};

struct LocalBrickOptions {
  /// The band (band > 0 or 0 for auto_band of the whole grid) with its truncation resolved on the
  /// whole grid (TruncationMode None, Given or Resolved: a block cannot see the whole's).
  BandOptions band;
  GradientOptions gradient;
  /// Contact points from the grid's lattice (lattice_contact_points.h), 1, or from the band's
  /// regular triangulation in certified bricks (brick_contact_points), 0; -1: auto_lattice_points
  /// of the whole grid (pipeline.h), and the triangulation with refine_zero_set.
  int lattice_points = -1;
  ContactPointOptions contact;          ///< the triangulation's contact points'
  ContactPointOptions lattice_contact;  ///< the lattice's
  LocalReconstructionOptions local;
  /// Lattice subdivisions of each triangle (2^s segments per edge), 0..4; -1: auto_subdivisions
  /// of the whole grid (pipeline.h).
  int subdivisions = -1;
  /// After the projection, one more level where the mesh's chords sag by more than this many
  /// spacings (an edge's length times its ends' normals' turn / 8), the new vertices projected
  /// too (with up to 3 subdivisions); 0: none; -1: auto_split_sag of the whole grid (pipeline.h).
  double split_sag = -1;
  /// The dual mesh on the grid at twice the resolution, with the parts thinner than a spacing
  /// that its samples straddle (a wing, a blade: no sign change between them) read from the
  /// contact points on their two sides, and one subdivision level fewer
  /// (reconstruction/local/thin_parts.h). Not with refine_zero_set. 1: on, 0: off, -1:
  /// auto_thin_parts of the whole grid's size alone (pipeline.h; contour() counts the grid's
  /// subspacing gaps first and passes 0 or 1).
  int thin_parts = -1;
  bool project = true;  ///< onto the contact points' local fit (contact_projection.h)
  /// ContourOptions::local_projection's: a tight neighbourhood, no residual limit, robust.
  ContactProjectionOptions projection = local_projection_options();
  /// Where the contact points lie on their fit's quadric (a surface smooth at the spacing's
  /// scale), each vertex keeps its chord offset: set again for its smaller triangles after the
  /// sag split, and left in place by the carving (not with edge fans, which do not carve).
  bool keep_chord_offsets = true;
  /// Carving, vertex by vertex: up to `carve_passes` rounds of each vertex pushed onto the sphere
  /// of the band sample's ball it enters deepest (sphere_carving.h without its triangle checks
  /// and rounds, which are whole-mesh stages).
  bool carve = true;
  int carve_passes = 3;
  /// Rounds that move the mesh's nearest feature off each band sample within a spacing of the
  /// surface that lies on the wrong side of it (carving's triangle rounds, for the sides alone).
  int side_rounds = kSideRounds;
  /// Vertices on the reconstruction's sharp features (feature vertices, and the subdivision's
  /// vertices between two of them) are neither projected nor carved. Off: at 64³ it sharpens
  /// the cube's edges (0.0125 -> 0.0083 h) and wingnut's (0.158 -> 0.148 h), but on a coarse
  /// grid a curved patch's cells read as features and stay chords (torus 32³: L1 0.176 -> 0.208
  /// of MC's, spot 0.236 -> 0.288).
  bool keep_features = false;
  /// Values that are no exact distances (a neural SDF, a TSDF: the contact points then miss):
  /// the vertices (those whose samples' mismatch exceeds zero_set.mismatch, if positive) move
  /// onto the zero set of the block's tricubic interpolant and are not carved
  /// (zero_set_refinement.h).
  bool refine_zero_set = false;
  ZeroSetRefinementOptions zero_set;
  /// Undo the projection's and carving's moves of the vertices of triangles that then cross
  /// another, in kUntangleRounds rounds (each over the triangles the last one changed).
  bool untangle = true;
  /// When set and it becomes true, the bricks stop soon (throws Cancelled).
  const std::atomic<bool>* cancel = nullptr;
  /// local_mesh_in_bricks: called as bricks finish (done, total), serialised; empty for silence.
  std::function<void(int, int)> progress;
  /// Called whenever a brick stops reading the grid: by local_brick_piece once it has read all
  /// it needs of its block (before the side checks; the caller may free the block's values
  /// then), and by local_mesh_in_bricks once a brick's block is copied out and after each brick.
  /// The pipeline drops a file-mapped grid's resident pages there, so that no more than a
  /// brick's block of the grid is held at a time.
  std::function<void()> grid_read;
  /// Keep the owned samples' contact points in LocalPiece (for adaptivity after the join).
  bool keep_contact_points = false;
  /// When set, the bricks take their contact points from here (the caller keeps them alive);
  /// `gradient`, `lattice_points`, `contact` and `lattice_contact` are then not read.
  const GivenContactPoints* given_points = nullptr;
  /// When set, the lattice's contact points that earlier bricks made are taken from here, and
  /// this brick's are added (local_mesh_in_bricks: each sample's point is made once, not again
  /// for every brick whose reach covers it). The bricks then run one at a time, in C order.
  /// Read only where the brick's contact points come from the lattice (local_lattice_points).
  detail::LatticePointStore* lattice_store = nullptr;
};

/// A vertex's global name: (k, 0) for the local reconstruction's vertex k (KeyedLocalMesh), (kx,
/// (ky + 1) * 64 + j) for the subdivision vertex j / 32 of the way along edge (kx, ky), kx < ky;
/// (2^63 + triangle, slot) for a vertex inside one of the reconstruction's triangles (its place
/// on the lattice of 32 segments per edge: the same name at every subdivision level).
using VertexKey = std::array<std::uint64_t, 2>;

/// The part of the mesh that one brick owns.
struct LocalPiece {
  PointMatrix vertices;         ///< v x 3, in ascending key order
  std::vector<VertexKey> keys;  ///< v, ascending and distinct
  TriangleMatrix triangles;     ///< outward oriented, indices into `vertices`
  /// Per triangle, ascending: 256 * (8 * its grid edge + rank in the edge's polygon) + its rank
  /// among that triangle's subdivisions (the whole grid's order).
  std::vector<std::uint64_t> triangle_names;
  long contact_points = 0;  ///< contact points of the block's flagged samples
  /// With keep_contact_points: the contact points of the owned samples (each sample's once over
  /// all bricks), their unit normals, and their samples' global C-order indices, ascending.
  PointMatrix owned_points, owned_normals;
  std::vector<std::uint64_t> owned_samples;
  LocalReconstructionStats stats;  ///< of the owned cells (those with their low corner owned)
  /// Seconds per step: band, contact points, reconstruction, subdivision and projection,
  /// carving, untangling (kLocalSteps names them).
  std::array<double, 6> seconds{};
};

/// The names of LocalPiece::seconds' steps.
constexpr std::array<const char*, 6> kLocalSteps{"band",           "contact points",
                                                 "reconstruction", "subdivision and projection",
                                                 "carving",        "untangling"};

/// Throws Error unless every vertex and triangle of a grid `dims` across (the whole grid's) has a
/// distinct 64-bit name (VertexKey, LocalPiece::triangle_names): a triangle's is 2048 times its
/// grid edge's index and more (3 edges a sample; the grid at twice the resolution with thin
/// parts), so the samples must stay under 2^64 / 6144 (3e15).
void require_nameable(const std::array<int, 3>& dims, const LocalBrickOptions& options);

/// Whether the bricks of a grid `dims` across (the whole grid's) make their contact points from
/// the lattice (LocalBrickOptions::lattice_points).
bool local_lattice_points(const LocalBrickOptions& options, const std::array<int, 3>& dims);

/// Whether the bricks of a grid `dims` across (the whole grid's) look for thin parts
/// (LocalBrickOptions::thin_parts; never with refine_zero_set).
bool local_thin_parts(const LocalBrickOptions& options, const std::array<int, 3>& dims);

/// The halo, in samples, that a brick's block needs first with these options on a grid of
/// whole-grid `dims` (the contact points' stars may ask for more: HaloTooSmall).
int local_brick_halo(const LocalBrickOptions& options, const std::array<int, 3>& dims);

/// The distance from the surface, in spacings of distance (values times the band's value_scale),
/// within which the bricks read the grid's values: the band with its margin, and the carving
/// band. Beyond it they read only the values' signs and that they lie beyond, so a sampler may
/// put any value of the right sign and larger size there (a callable's bound).
double local_values_reach(const LocalBrickOptions& options, const std::array<int, 3>& dims);

/// The piece owned by the edges with global low sample in [own_first, own_end) of the grid that
/// `block` is a block of (GridGeometry::first and ::whole set; the block should reach
/// local_brick_halo samples beyond the owned range where the grid goes on). Throws HaloTooSmall
/// if the block is too small for a star it needs, Error for bad options or values.
LocalPiece local_brick_piece(const GridView& block, const std::array<int, 3>& own_first,
                             const std::array<int, 3>& own_end, const LocalBrickOptions& options);

/// A grid read a block at a time, for the bricks' halo loop.
struct BlockSource {
  std::array<int, 3> dims{};  ///< the whole grid's samples per axis
  /// Views the samples [lo, hi) as a block of the whole grid (GridGeometry::first = lo, ::whole =
  /// dims); the view stays valid until the next read or release.
  std::function<GridView(const std::array<int, 3>& lo, const std::array<int, 3>& hi)> read;
  /// Called once a brick has read all it needs of the last block: frees it, or keeps its storage
  /// for the next read; may be empty.
  std::function<void()> release;
  /// The grid itself, where it is in memory: a block that would be all of it is not read.
  const GridView* whole = nullptr;
};

/// The piece owned by the edges with low sample in [own_first, own_end) of `source`'s grid, its
/// block read with local_brick_halo's halo, which doubles while the block is too small for a
/// star (HaloTooSmall); `wider` (optional) counts the doublings. What local_mesh_in_bricks does
/// per brick, and what the Python module's and Dask's bricks call.
LocalPiece local_brick_piece(const BlockSource& source, const std::array<int, 3>& own_first,
                             const std::array<int, 3>& own_end, const LocalBrickOptions& options,
                             int* wider = nullptr);

/// Joins pieces: vertices with equal keys become one (ascending keys), triangles in the order of
/// their names: the same arrays whatever the bricks. Throws InternalError if two pieces give one
/// key two positions.
Mesh join_local_pieces(const std::vector<LocalPiece>& pieces);
/// The same, freeing each piece's arrays as soon as they are read (`pieces` is left empty).
Mesh join_local_pieces(std::vector<LocalPiece>&& pieces);

/// The whole grid's mesh from bricks of `brick` samples per side (0: one brick), computed one
/// after another, each in parallel inside (so memory holds one brick's work and the pieces so
/// far), and joined; each brick's halo doubles until its stars fit. The mesh does not depend on
/// `brick` or the thread count.
struct LocalBricksStats {
  int bricks = 0;                   ///< bricks with a piece of the surface
  int wider_halos = 0;              ///< bricks read again with a wider halo
  bool thin_parts = false;          ///< whether they looked for thin parts (local_thin_parts)
  bool lattice_points = false;      ///< whether they made lattice contact points
  long contact_points = 0;          ///< over all bricks (a halo's samples counted again)
  LocalReconstructionStats local;   ///< summed over the bricks' owned cells
  std::array<double, 6> seconds{};  ///< LocalPiece::seconds summed over the bricks
};

/// `contact_points` (optional, with options.keep_contact_points): every brick's owned contact
/// points joined in sample order (the same for any bricks).
Mesh local_mesh_in_bricks(const GridView& grid, const LocalBrickOptions& options, int brick = 0,
                          LocalBricksStats* stats = nullptr,
                          OrientedPoints* contact_points = nullptr);

/// The same for a grid read a block at a time (each brick's block with its halo, float32); its
/// band's truncation must be resolved already (TruncationMode None, Given or Resolved: the whole
/// grid is never read at once). Bricks whose own samples, grown by one, cannot hold the surface
/// (BlockedGrid::may_hold_surface) are not read.
Mesh local_mesh_in_bricks(const BlockedGrid& grid, const LocalBrickOptions& options, int brick,
                          LocalBricksStats* stats = nullptr,
                          OrientedPoints* contact_points = nullptr);

/// The pieces' owned contact points (LocalPiece::owned_points) in their samples' order.
OrientedPoints join_owned_contact_points(const std::vector<LocalPiece>& pieces);

}  // namespace sdfcontour
