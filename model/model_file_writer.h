// Writing a model file (TOML, the contract's format; docs/model-file.md) from a Model.
//
// The inverse of read_model(): [matrices] names the mass and stiffness Matrix Market files
// (and dof_labels when the model has labels), each distinct joint element becomes its
// section ([iwan.<name>] with Fs, Kt, chi, beta; [spring] with one key per spring) and every
// joint a [[joint]] table with 0-based indices ("ground" for the ground end), or
// "node:component" labels when the model has them. Numbers are written with the shortest
// representation that reads back exactly, always as TOML floats. Matrices either are
// referenced where they already are (paths written relative to the model file's directory
// when possible) or written beside the model file (17 significant digits, lossless).
// Every file is written atomically.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "jointlab/model/model_file.h"

namespace jointlab::model {

/// Where the written model file finds its matrices.
struct ModelFileMatrices {
  std::filesystem::path mass;        ///< existing M file to reference; empty: write "mass.mtx"
  std::filesystem::path stiffness;   ///< existing K file to reference; empty: write "stiffness.mtx"
  std::filesystem::path dof_labels;  ///< existing labels file; empty: write "dof_labels.csv"
                                     ///< (only when the model has labels)
};

/// Comments a model file carries for a person (they do not change what it describes).
struct ModelFileComments {
  std::vector<std::string> header;  ///< lines before [matrices], each written as "# <line>"
  std::vector<std::string> joints;  ///< per joint (model.joints order) a note, or empty
};

/// `x` as a TOML float: the shortest representation that reads back exactly, never an
/// integer literal; logic_error for a non-finite number (the format has none for a model).
std::string toml_float(double x);

/// The model file text for `model`, with the matrix paths as given (written verbatim).
std::string model_file_text(const Model& model, const std::string& mass_path,
                            const std::string& stiffness_path, const std::string& labels_path,
                            const ModelFileComments& comments = {});

/// Writes `model` as a model file at `path` (and its matrices, where `files` leaves them empty);
/// InputError if a file cannot be written or an element name cannot be expressed in the format.
void write_model_file(const std::filesystem::path& path, const Model& model,
                      const ModelFileMatrices& files = {}, const ModelFileComments& comments = {});

}  // namespace jointlab::model
