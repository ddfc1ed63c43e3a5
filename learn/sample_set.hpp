#pragma once
/// \file
/// Input/output sample pairs for training a network, and a seeded random split of them (the 70/30
/// train/test split of §5.3.3-5.3.4, and the train/validation split the trainer's early stopping
/// uses).

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace softkin {

/// Row i of X (#samples x #inputs) maps to row i of Y (#samples x #outputs), original units.
struct SampleSet {
  Eigen::MatrixXd X;
  Eigen::MatrixXd Y;
  int size() const { return static_cast<int>(X.rows()); }
  bool empty() const { return X.rows() == 0; }
};

/// The two index lists of a split of {0, ..., n-1}.
struct SplitIndices {
  std::vector<int> first;   ///< round(fraction n) indices, ascending
  std::vector<int> second;  ///< the other n - round(fraction n), ascending
};

/// Seeded random split: a Fisher-Yates shuffle of 0..n-1 driven by std::mt19937_64(seed) (with
/// portable integer draws), whose first round(fraction n) entries form `first`; both lists are
/// then sorted. Same (n, fraction, seed), same split, on every platform. Throws
/// std::invalid_argument unless n >= 0 and 0 <= fraction <= 1.
SplitIndices RandomSplit(int n, double fraction, std::uint64_t seed);

/// The rows `rows` of s (each in [0, s.size()), in the given order). Throws std::invalid_argument
/// for an index out of range or X/Y with different row counts.
SampleSet SelectRows(const SampleSet& s, const std::vector<int>& rows);

}  // namespace softkin
