// Spearman's rank correlation.
//
// The ranks of n values are 0 .. n-1 in ascending order of value; equal values are ranked in
// the order they are given (a stable sort), not given their mean rank, so the ranks are always
// a permutation of 0 .. n-1. Spearman's rho is the Pearson correlation of two samples' ranks,
// dimensionless in [-1, 1]: +1 when both rise together, -1 when one falls as the other rises.
// For ranks that are a permutation it equals 1 - 6 sum d_i^2 / (n (n^2 - 1)), d_i the
// difference of point i's two ranks; in floating point the two forms differ in the last bit
// for about half the values (rounded once against twice), so each caller keeps the form its
// thresholds were set with: rank_correlation the Pearson form, rank_trend the closed one.
#pragma once

#include <vector>

namespace jointlab {

/// Ranks 0 .. n-1 of `v` in ascending order of value, equal values ranked in the order given.
std::vector<double> ranks(const std::vector<double>& v);

/// Spearman's rank correlation of `a` and `b` (equal sizes, at least 2): the Pearson
/// correlation of their ranks (ranks()).
double rank_correlation(const std::vector<double>& a, const std::vector<double>& b);

/// Spearman's rank correlation of `x` with its index 0 .. n-1 (ties broken by order; n at least
/// 2), as 1 - 6 sum d^2 / (n (n^2 - 1)): +1 rising, -1 falling.
double rank_trend(const std::vector<double>& x);

}  // namespace jointlab
