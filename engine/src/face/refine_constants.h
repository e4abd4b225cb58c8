#pragma once
// The face refinement's tuning constants, one line each: the rule and why. What was measured to
// choose them, and what was tried instead, is in docs/TUNING.md.
#include <cstddef>
#include <cstdint>

namespace rdmesh {

// --- Splits (refiner_split.cpp)
// A split point keeps at least this barycentric weight on every corner (no slivers at birth).
constexpr double kMinWeight = 0.04;
// An optimum closer to an edge than this weight splits that edge instead (the paper's Alg. 3).
constexpr double kEdgeWeight = 0.12;
// A triangle this many splits deep that still violates is not split again (no-progress guard).
constexpr int kMaxGeneration = 24;
// ... unless its longest edge exceeds this fraction of the face box's diagonal (still large).
constexpr double kLargeAtCap = 0.1;
// A fold shorter than the deviation and within it is not split below this depth (no progress).
constexpr int kSmallFoldGeneration = 6;
// A fold that this many splits in a row each handed on to a child is left unsplit (as is one
// across which the surface's normal jumps, after one): splits do not remove it (SSO-4's bow-tie
// B-splines, whose normal reverses inside, went kMaxGeneration deep along the fold line: 16,168
// triangles on a face of 0.14 mm2). 4 left ESP-WROOM-02 3 inverted triangles and the toroid
// L39.4 7, where 5 leaves 0 and 6 (docs/TUNING.md).
constexpr int kFoldRun = 5;
// The final check (Refiner::Verify) splits in at most this many rounds.
constexpr int kVerifyRounds = 6;
// ... and off the surface, where it also checks against the face's own surface, this many.
constexpr int kOwnVerifyRounds = 16;
// Below this shape quality (1 = equilateral) a triangle to refine is a sliver: reshape it first.
constexpr double kSliverQuality = 0.02;
// A reshaping flip must raise its triangle's normal agreement by this much (no churn).
constexpr double kReshapeGain = 1e-3;

// --- Measures and cavities (refiner.cpp)
// Splits of standing triangles may fold children only in the first generations.
constexpr int kFoldingGenerations = 1;
// The violation given to a folded triangle: worse than any honest miss, so it is refined first.
constexpr double kFoldViolation = 4.0;

// --- Improvement (refiner_improve.cpp)
// A collapse over the criteria by up to this factor is retried with its survivor moved (rarely
// succeeds beyond; each try costs a smoothing search).
constexpr double kCollapseSlack = 1.6;
// At most this many flip passes before Settle's rounds; they stop at one that flips nothing.
constexpr int kSettleFlipPasses = 5;
// Improve stops after a round that collapses at most 1 / this of the nodes (later rounds pay
// little).
constexpr int kStopCollapseDivisor = 50;
// A mover's search stops once its ring is within this fraction of the criteria (leaves slack for
// the next collapses).
constexpr double kMoverEnough = 0.9;
// After the survivor's move, an attempt still over the criteria by this factor is given up.
constexpr double kGiveUpAfterSurvivor = 1.1;
// Rounds after this many smooth only near their collapses (smoothing everywhere mostly churns).
constexpr int kSmoothEverywhereRounds = 1;

// --- The face mesher's retries (face_mesher.cpp)
// How many times a face left over its criteria is refined again from its own result.
constexpr int kStuckRetries = 2;
// Stuck folds from which a face is a twisted patch rather than a fan across a turn: its retries
// are skipped (face_mesher.cpp, StuckOnFolds).
constexpr int64_t kStuckFoldsPatch = 16;
// A folded first triangulation's own refinement stops at this many times the triangles the
// unfolded start's splits made (at least kFoldedStartMin).
constexpr int64_t kFoldedStartCap = 4;
constexpr int64_t kFoldedStartMin = 100;
// The other retries of a face still over its criteria (a first triangulation that follows the
// surface's turn, a refinement from its own result) stop at this many times its triangles (at
// least kRetryMin): past that they only chase a fold no split removes.
constexpr int64_t kRetryCap = 4;
constexpr int64_t kRetryMin = 100;
// A sphere's seed lattice is settled by this many rounds of flips and smoothing before refining.
constexpr int kLatticeSettleRounds = 4;
// A face still stuck is refined once more from a first triangulation whose triangles turn by at
// most this much between corner normals (as SeedPoints' cells, give or take), seeded in at most
// this many rounds, with at most this many seeds per boundary node (at least the minimum).
constexpr double kTurnStartMaxTurn = 0.7853981633974483;  // pi / 4
constexpr int kTurnStartRounds = 12;
constexpr size_t kTurnStartSeedFactor = 20;
constexpr size_t kTurnStartMinSeeds = 2000;

// --- Off the surface (face_mesher.cpp)
// BendSide's difference steps, as a share of the face's (u,v) extent in each direction.
constexpr double kBendStep = 1e-4;
// A principal curvature of the other sign below this share of the largest counts as none (a
// near-cylinder's noise); the check against the surface catches what that lets through.
constexpr double kBendTolerance = 0.02;
// A face that bends one way in parts is read on a grid of this many cells a side over its (u,v)
// bounds (OffsetWhereItBendsOneWay).
constexpr int kOffsetFieldCells = 24;

}  // namespace rdmesh
