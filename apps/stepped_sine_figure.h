// The figure of `jointlab stepped-sine --figure`: stepped-sine points with their
// uncertainties over ring-down backbones (process output), frequency and damping versus
// amplitude. Drawn with PLplot's cairo drivers (.png, .svg, .pdf), written atomically.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace jointlab::apps {

/// One set of backbone points or one ring-down curve.
struct FigureSeries {
  std::string label;                 ///< legend entry
  Eigen::VectorXd amplitude;         ///< [SI of the amplitude quantity]
  Eigen::VectorXd frequency_hz;      ///< [Hz]
  Eigen::VectorXd damping;           ///< damping ratio
  Eigen::VectorXd frequency_std_hz;  ///< k sigma, drawn as error bars (points only)
  Eigen::VectorXd damping_std;       ///< k sigma
  bool points = true;                ///< symbols with error bars; false: a line
};

/// Draws the series into `file`; InputError when the file cannot be written.
void plot_sine_figure(const std::vector<FigureSeries>& series, const std::string& title,
                      const std::string& amplitude_label, const std::filesystem::path& file);

}  // namespace jointlab::apps
