// Test-only: the lowest modes of a free structure, rigid-body modes included.
#pragma once

#include <gtest/gtest.h>
#include <Eigen/SparseCore>

#include "jointlab/model/sparse_eigen.h"

namespace jointlab::testing {

/// The `count` lowest eigenpairs of K phi = lambda M phi by shift-invert below zero (under the
/// rigid-body modes, lambda = 0); a test failure, with the solver's report, when they do not
/// converge.
inline model::EigenResult free_modes(const Eigen::SparseMatrix<double>& stiffness,
                                     const Eigen::SparseMatrix<double>& mass, int count) {
  model::EigenOptions o;
  o.count = count;
  o.shift = -1.0;
  model::EigenResult r = model::lowest_modes(stiffness, mass, o);
  EXPECT_TRUE(r.summary.ok()) << r.summary.report;
  return r;
}

}  // namespace jointlab::testing
