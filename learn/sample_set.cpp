#include "softkin/learn/sample_set.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>

namespace softkin {

namespace {

// Uniform integer in [0, bound) from a 64-bit engine, by rejection (portable, unbiased).
std::uint64_t UniformIndex(std::mt19937_64& rng, std::uint64_t bound) {
  const std::uint64_t limit =
      std::numeric_limits<std::uint64_t>::max() - std::numeric_limits<std::uint64_t>::max() % bound;
  std::uint64_t r = rng();
  while (r >= limit) r = rng();
  return r % bound;
}

}  // namespace

SplitIndices RandomSplit(int n, double fraction, std::uint64_t seed) {
  if (n < 0)
    throw std::invalid_argument("RandomSplit: n = " + std::to_string(n) + ", expected >= 0");
  if (!(fraction >= 0.0 && fraction <= 1.0))
    throw std::invalid_argument("RandomSplit: fraction = " + std::to_string(fraction) +
                                ", expected in [0, 1]");
  std::vector<int> order(n);
  for (int i = 0; i < n; ++i) order[i] = i;
  std::mt19937_64 rng(seed);
  for (int i = n - 1; i > 0; --i) {
    const int j = static_cast<int>(UniformIndex(rng, static_cast<std::uint64_t>(i) + 1));
    std::swap(order[i], order[j]);
  }
  const int n_first = static_cast<int>(std::lround(fraction * n));
  SplitIndices split;
  split.first.assign(order.begin(), order.begin() + n_first);
  split.second.assign(order.begin() + n_first, order.end());
  std::sort(split.first.begin(), split.first.end());
  std::sort(split.second.begin(), split.second.end());
  return split;
}

SampleSet SelectRows(const SampleSet& s, const std::vector<int>& rows) {
  if (s.X.rows() != s.Y.rows())
    throw std::invalid_argument("SelectRows: X has " + std::to_string(s.X.rows()) +
                                " rows but Y has " + std::to_string(s.Y.rows()));
  SampleSet out;
  out.X.resize(static_cast<Eigen::Index>(rows.size()), s.X.cols());
  out.Y.resize(static_cast<Eigen::Index>(rows.size()), s.Y.cols());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const int r = rows[i];
    if (r < 0 || r >= s.size())
      throw std::invalid_argument("SelectRows: row index " + std::to_string(r) + " (entry " +
                                  std::to_string(i) + ") outside [0, " + std::to_string(s.size()) +
                                  ")");
    out.X.row(static_cast<Eigen::Index>(i)) = s.X.row(r);
    out.Y.row(static_cast<Eigen::Index>(i)) = s.Y.row(r);
  }
  return out;
}

}  // namespace softkin
