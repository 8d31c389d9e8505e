// Figures of a test campaign, drawn with PLplot's cairo drivers.
//
// Each figure is one function: data in, file out. The file's extension picks the driver:
// .png -> pngcairo (reports), .svg -> svgcairo and .pdf -> pdfcairo (papers). Every call
// opens its own PLplot stream (plmkstrm), draws black on white and closes the stream
// (plend1), restoring the caller's current stream, so no PLplot state outlives a call.
// Logarithmic axes take log10 of the data; non-positive values are left out of them.
// Units are those of the data passed in; the labels passed in should name them.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "jointlab/campaign/scatter.h"

namespace jointlab::campaign {

/// Size of a figure.
struct FigureSize {
  int width = 900;   ///< [pixels for PNG; points x 1.25 for SVG and PDF]
  int height = 700;  ///< same units as width
};

/// A model curve (QSMA) in the measured amplitude's units.
struct ModelCurve {
  std::string label;             ///< legend entry ("model, updated")
  Eigen::VectorXd amplitude;     ///< amplitude [SI of the measured amplitude]
  Eigen::VectorXd frequency_hz;  ///< natural frequency [Hz]
  Eigen::VectorXd damping;       ///< damping ratio
};

/// Stepped-sine points of one file with their uncertainties (as written: k sigma).
struct SinePoints {
  std::string label;                 ///< legend entry ("stepped sine sweeps")
  Eigen::VectorXd amplitude;         ///< amplitude [SI of the measured amplitude]
  Eigen::VectorXd frequency_hz;      ///< natural frequency [Hz]
  Eigen::VectorXd damping;           ///< damping ratio
  Eigen::VectorXd frequency_std_hz;  ///< uncertainty of the frequency [Hz]
  Eigen::VectorXd damping_std;       ///< uncertainty of the damping ratio
};

/// Frequency and damping versus amplitude of one mode: every hit faint, the binned mean
/// and its confidence band, stepped-sine points with their bars, and model curves.
struct BackboneFigure {
  std::string title;                     ///< top line ("mode 1, acc_9003_z")
  std::string amplitude_label;           ///< x axis ("velocity amplitude [m/s]")
  std::vector<Curve> hits;               ///< every hit's backbone
  ScatterSummary summary;                ///< bins (mean and interval) and flagged hits
  std::vector<ModelCurve> model;         ///< model curves, drawn in the data's amplitude range
  std::vector<SinePoints> stepped_sine;  ///< stepped-sine points of the mode
};

/// Draws a BackboneFigure (frequency above, damping on a log axis below) into `file`.
void plot_backbones(const BackboneFigure& figure, const std::filesystem::path& file,
                    const FigureSize& size = {1150, 700});

/// A shaded frequency band with its label.
struct LabelledBand {
  std::string label;  ///< text above the band ("mode 1")
  double lo_hz = 0;   ///< lower edge [Hz]
  double hi_hz = 0;   ///< upper edge [Hz]
};

/// Amplitude spectra of one record's channels with the analysis bands.
struct SpectrumFigure {
  std::string title;                       ///< top line
  std::string amplitude_label;             ///< y axis ("amplitude [m/s^2]")
  Eigen::VectorXd frequency_hz;            ///< bin frequencies [Hz]
  std::vector<std::string> channel_names;  ///< one per spectrum
  std::vector<Eigen::VectorXd> spectra;    ///< amplitude per bin, per channel
  std::vector<LabelledBand> bands;         ///< shaded bands
  double max_frequency_hz = 0;             ///< right end of the axis; 0: all
};

/// Draws a SpectrumFigure (log amplitude) into `file`.
void plot_spectrum(const SpectrumFigure& figure, const std::filesystem::path& file,
                   const FigureSize& size = {});

/// A cell of a MAC matrix: (row, column).
using MacCell = std::pair<int, int>;

/// Draws a MAC matrix (rows: measured modes, columns: model modes) as grey cells with
/// their values, the `marked` cells (the pairs) framed in red, into `file`.
void plot_mac(const Eigen::Ref<const Eigen::MatrixXd>& mac, const std::vector<std::string>& rows,
              const std::vector<std::string>& columns, const std::string& title,
              const std::filesystem::path& file, const FigureSize& size = {},
              const std::vector<MacCell>& marked = {});

/// One line of a LinePanel; a point without a y value breaks the line.
struct LineSeries {
  std::string label;                     ///< legend entry
  std::vector<double> x;                 ///< abscissae
  std::vector<std::optional<double>> y;  ///< ordinates (none: a gap)
};

/// One panel of line plots with a legend.
struct LinePanel {
  std::string title;                  ///< above the panel
  std::string x_label, y_label;       ///< axis labels with units
  bool log_x = false, log_y = false;  ///< logarithmic axes (non-positive values left out)
  std::vector<LineSeries> series;     ///< the lines
  std::vector<double> marks_x;        ///< vertical lines (the result), in x units
  std::string marks_label;            ///< legend entry of the vertical lines
};

/// Draws panels of lines, two columns when there are more than two (sharing the legend of the
/// top right panel: give every panel the same series), into `file`.
void plot_panels(const std::vector<LinePanel>& panels, const std::string& title,
                 const std::filesystem::path& file, const FigureSize& size = {1150, 800});

/// One set of relative errors, one per mode.
struct ErrorSeries {
  std::string label;            ///< legend entry ("before updating")
  std::vector<double> percent;  ///< (model - test) / test x 100, one per mode
};

/// Draws grouped bars of linear frequency errors [%] per mode into `file`.
void plot_frequency_errors(const std::vector<std::string>& modes,
                           const std::vector<ErrorSeries>& series, const std::string& title,
                           const std::filesystem::path& file, const FigureSize& size = {});

}  // namespace jointlab::campaign
