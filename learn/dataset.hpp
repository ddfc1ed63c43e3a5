#pragma once
/// \file dataset.hpp
/// Datasets for the learned kinematics (thesis Sec. 5.3.2): samples (c, p(c), J(c)) of any
/// Kinematics, written to a CSV as they are computed, resumable and shardable, and a loader that
/// returns Eigen matrices for training (docs/datasets.md).
///
/// Sampling. Grid: N values per actuator, c_a = lower_a + (upper_a - lower_a) k / (N - 1),
/// k = 0..N-1, N^m samples visited in serpentine (boustrophedon, reflected mixed-radix Gray code)
/// order: actuator 0 varies fastest, and consecutive samples differ by one grid step in exactly
/// one actuator, so a warm-started simulator starts every solve next to its answer. Random: n
/// samples uniform in the box, sample i drawn from a counter-based generator keyed by (seed, i),
/// so any slice can be computed without the samples before it.
///
/// Warm-start blocks. The generation order is cut into blocks of `block` samples; the kinematics
/// is reset (the `reset` hook: SimulatorKinematics::Reset, TwinKinematics::Reset) at the start of
/// every block, so each sample's value depends only on its block. A resumed run restarts at the
/// block of the first missing sample (recomputing, not rewriting, the samples of that block that
/// are already in the file), and shards are whole blocks: a resumed or sharded-and-merged dataset
/// equals an uninterrupted one sample for sample, bit for bit (given a deterministic kinematics).
///
/// CSV format (one header line, then one line per sample in generation order, '\n' endings,
/// numbers in %.17g so they read back exactly):
///   index,status,c0..c{m-1},<point>_x,<point>_y,<point>_z ...,J_<point>_<x|y|z>_c<a> ...,message
/// `index` is the sample's position in the generation order (0-based, over the whole dataset,
/// also in a shard). `status` is `ok`, `inverted` or `failed`; a failed sample (the kinematics
/// returned ok = false) has empty p and J fields and the reason in `message` (commas and line
/// breaks replaced by ';' and ' '); an inverted sample has p and J of a simulated state with
/// inverted body elements (KinematicsEval::inverted_elements > 0: not a physical answer), and
/// their count and smallest volume ratio in `message`; an ok sample has an empty message. No
/// field is ever NaN. The loader leaves failed and inverted samples out of training.
/// Jacobian columns (only when the dataset has Jacobians) flatten the 3P x m matrix J = dp/dc
/// row-major: column (3 q + d) m + a is dp_{q,d}/dc_a (point q, coordinate d = x, y, z,
/// actuator a), named J_<point>_<coord>_c<a>.
/// The sidecar `<csv>.json` holds {"format": "softkin-dataset", "version": 1, "config": {...},
/// "shard": {...}, "provenance": {...}}: `config` identifies the dataset (source, points,
/// actuator bounds, sampling, jacobian, block) and must match on resume and merge; `provenance`
/// (git commit, command, ...) is recorded only.
#include "softkin/ik/kinematics.hpp"
#include "softkin/learn/sample_set.hpp"

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace softkin {

/// How a dataset samples the actuation box.
struct DatasetSampling {
  enum class Kind { kGrid, kRandom };
  Kind kind = Kind::kGrid;
  int grid = 16;           ///< N, values per actuator (grid), >= 2
  long long random = 0;    ///< number of samples (random), >= 1
  std::uint64_t seed = 0;  ///< random sampling seed
  int block = 64;          ///< warm-start block length (samples), >= 1
  bool IsValid(std::string* why) const;
  /// {"kind": "grid", "grid": N, "block": B} or {"kind": "random", "samples": n, "seed": s, ...}.
  nlohmann::json ToJson() const;
};

/// Number of samples: grid^m or random. Throws std::invalid_argument if it exceeds 2^40.
long long DatasetSize(const DatasetSampling& s, int num_actuators);

/// Grid digits (k_0, ..., k_{m-1}), each in [0, N), of sample i of the serpentine order.
std::vector<int> SerpentineDigits(long long i, int grid, int num_actuators);

/// Actuation of sample i (#actuators, within [lower, upper]) in generation order.
Eigen::VectorXd DatasetActuation(const DatasetSampling& s, const Eigen::VectorXd& lower,
                                 const Eigen::VectorXd& upper, long long i);

/// The contiguous slice [first, first + count) of the generation order that shard k of n
/// computes: whole warm-start blocks, the blocks split as evenly as possible, in order.
struct ShardRange {
  long long first = 0, count = 0;
};
ShardRange DatasetShard(long long total, int block, int k, int n);

/// What a generation run is asked to do.
struct DatasetRunOptions {
  std::string out;            ///< CSV path; the sidecar is out + ".json"
  bool jacobian = false;      ///< also record J (the kinematics must provide it)
  int shard = 0, shards = 1;  ///< compute shard `shard` of `shards` (0-based)
  /// Identifies the data source in the sidecar's config (robot, res, params, twin label, ...).
  nlohmann::json source;
  /// Recorded in the sidecar, not compared (git commit, command line).
  nlohmann::json provenance;
  /// Forgets the kinematics' warm-start state (nullptr: the kinematics has none).
  std::function<void()> reset;
  bool progress = true;  ///< progress bar on stderr
  /// Stop after writing this many new samples (< 0: never); simulates an interruption in tests.
  long long stop_after = -1;
  /// Called after each sample is evaluated (written or recomputed for a warm start), e.g. for
  /// the MPI dispatcher to answer the other ranks between samples (experiments/dataset_mpi.hpp).
  std::function<void()> after_sample;
};

/// What a run did.
struct DatasetRunSummary {
  long long first = 0, count = 0;  ///< the shard's slice of the generation order
  long long already = 0;           ///< samples found complete in the file (resume)
  long long written = 0;           ///< samples written by this run
  long long failed = 0;            ///< of them, failed evaluations
  long long inverted = 0;          ///< of them, states with inverted body elements
  double time_s = 0;               ///< wall time of this run
  long long fk_solves = 0;         ///< forward solves of this run
};

/// Evaluates `kin` on the dataset samples of the shard and appends them to opt.out, flushing each
/// line. If opt.out exists, its sidecar must hold the same config and shard (else
/// std::invalid_argument naming the differing key); its complete lines are kept (a truncated
/// last line is dropped) and the run continues after them. Throws std::invalid_argument for a
/// bad option or a malformed existing file (file:line), std::runtime_error if a file cannot be
/// written.
DatasetRunSummary GenerateDataset(Kinematics& kin, const DatasetSampling& sampling,
                                  const DatasetRunOptions& opt);

/// Concatenates complete shard files (any order on the command line) into `out` in shard order,
/// with a sidecar for the whole dataset. Throws std::invalid_argument if the shards' configs
/// differ, a shard is missing or duplicated, or a shard is incomplete (naming the file).
/// Returns the number of samples written.
long long MergeDatasets(const std::vector<std::string>& shards, const std::string& out);

/// A dataset loaded for training: only the ok samples (not failed, not inverted), in file order.
struct Dataset {
  std::vector<std::string> point_names;  ///< P tracked points
  int num_actuators = 0;                 ///< m
  Eigen::MatrixXd inputs;                ///< n x m actuations
  Eigen::MatrixXd positions;             ///< n x 3P, point-major (x, y, z per point), mm
  Eigen::MatrixXd jacobians;             ///< n x 3Pm (row-major J, see the file comment), or n x 0
  std::vector<long long> index;          ///< n generation-order indices
  long long failed = 0;                  ///< failed samples skipped
  long long inverted = 0;                ///< samples with inverted elements skipped
  nlohmann::json meta;                   ///< the sidecar (null if there is none)
};

/// Reads a dataset CSV (and its sidecar if present). Throws std::invalid_argument with file:line
/// for a malformed header or line (field count, non-number, non-finite value, unknown status,
/// indices not strictly increasing, a last line without '\n').
Dataset LoadDataset(const std::string& path);

/// Checks that a dataset read from `csv_path` carries the sidecar `softkin dataset` writes and that
/// it describes this CSV: the same tracked points, one bound pair per actuator, and every sample's
/// actuation within those bounds (to 1e-9 of the range). Throws std::invalid_argument naming the
/// sidecar and the key that does not match (a missing sidecar, or one copied from another robot,
/// would give a network wrong bounds and provenance).
void CheckSidecarMatches(const Dataset& d, const std::string& csv_path);

/// The dataset as network samples (learn/sample_set.hpp): X = inputs (n x m), Y = positions
/// (n x 3P, for N_fk).
SampleSet PositionSamples(const Dataset& d);
/// X = inputs, Y = flattened Jacobians (n x 3Pm, for N_J). Throws std::invalid_argument if the
/// dataset has no Jacobian columns.
SampleSet JacobianSamples(const Dataset& d);

/// A train/test split of a sample set.
struct TrainTestSets {
  SampleSet train, test;
  std::vector<int> train_rows, test_rows;  ///< rows of the input set, ascending, disjoint
};
/// The seeded split of Sec. 5.3.3 (70/30 by default): RandomSplit(s.size(), train_fraction, seed).
/// The same seed gives the same split on every platform.
TrainTestSets SplitTrainTest(const SampleSet& s, std::uint64_t seed, double train_fraction = 0.7);

}  // namespace softkin
