// Matrix Market files (NIST exchange format) for the mass and stiffness matrices.
//
// A file opens with the banner "%%MatrixMarket matrix <format> <field> <symmetry>":
// format "coordinate" (rows of "i j value", 1-based indices, after a size line
// "rows cols nnz") or "array" (values column by column after "rows cols"); field
// "real", "double" or "integer" (complex and pattern are refused); symmetry
// "general" or "symmetric". A symmetric file stores the lower triangle only
// (coordinate: entries with i >= j; array: column j from row j down) and the reader
// mirrors it. Duplicate coordinate entries are summed, as the format specifies.
// Lines starting with '%' after the banner are comments. Values are dimensionless
// to this layer; the caller knows their units (kg, N/m for M and K in SI).
// Every size the file declares is checked against what it costs before allocating.
// Own reader rather than CHOLMOD's cholmod_read_sparse (linked): that one allocates the
// declared entry count before reading and reports defects without file, line or field.
#pragma once

#include <filesystem>

#include <Eigen/SparseCore>

namespace jointlab::data {

/// Reads a real Matrix Market file (coordinate or array; general or symmetric) into a sparse
/// matrix; InputError naming file and line on any defect, or on more than `max_dimension`
/// rows or columns (refused before anything is allocated).
Eigen::SparseMatrix<double> read_matrix_market(const std::filesystem::path& path,
                                               long max_dimension = 100'000'000);

/// Writes a sparse matrix in coordinate format (symmetric: lower triangle only, with the
/// 'symmetric' qualifier), atomically, 17 significant digits.
void write_matrix_market(const std::filesystem::path& path, const Eigen::SparseMatrix<double>& m,
                         bool symmetric);

}  // namespace jointlab::data
