// A measured modes table (docs/modes.md), read against the channel names of a sensors file:
//     mode,frequency_hz[,<channel>...]
// one row per mode, optional shape entries per channel (every channel named in `channels`; empty
// cells and channels without a column are 0), delimited by ',', ';' or tab (the header's most
// frequent). An entry is real or complex (`0.1+0.2i`, `0.1-0.2j`, `(0.1+0.2j)`, `(0.1,0.2)`), or
// a channel is given as two columns of its real and imaginary parts (`<channel>_re`,
// `<channel>_im`; also `_real`/`_imag`, any case, after '_', '.' or ' '). The mode column may be
// headed as test-modal tools write it (`Mode #`, `Mode No.`, `mode_nr`), the frequency as
// `Frequency [Hz]`, `f (kHz)`, `fn_Hz` (converted to Hz); a frequency without a unit or in rad/s is
// refused saying to give Hz. Columns of damping, MPC, MPD, MCF, MOV or modal mass (any case, a
// unit in brackets allowed) are left out; any other column that is not a channel is refused
// naming the channels. Read here, with the other readers; the realisation of complex shapes and
// the pairing with a model are correlate/'s (measured_data.h, linear_update.h).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace jointlab::data {

/// A modes table as read: per row its mode number, frequency [Hz] and complex shape.
struct ModesTable {
  std::string source;            ///< the file it was read from
  std::vector<int> modes;        ///< mode numbers, in row order, each once, >= 1
  std::vector<long> lines;       ///< each mode's line in the file (for messages)
  Eigen::VectorXd frequency_hz;  ///< f per mode [Hz], > 0
  Eigen::MatrixXcd shapes;       ///< channels x modes, 0 where a channel has no entry
};

/// Reads a modes table whose shape columns name `channels` (a sensors file's, in its order:
/// the rows of ModesTable::shapes); InputError "file:line: what" naming the cell or column.
ModesTable read_modes_table(const std::filesystem::path& path,
                            const std::vector<std::string>& channels);

}  // namespace jointlab::data
