#pragma once
/// \file
/// The native file format `.tbs` (JSON, documented in docs/format.md) and atomic file output.

#include <tbs/atlas.h>
#include <tbs/spline.h>

#include <string>
#include <string_view>
#include <vector>

namespace tbs {

/// The newest version of the .tbs format this library reads and writes: 2 adds the atlas.
/// Files without an atlas are written as version 1, as before atlases, so that older readers
/// read them; a file with seams is version 2, which older readers refuse instead of reading
/// a closed surface as separate sheets.
inline constexpr int kTbsFormatVersion = 2;

/// A spline as stored in a .tbs file.
struct SplineFile {
  Spline spline;
  /// Length unit of the control points: one of mm, cm, m, um, in, ft, unitless.
  std::string units = "unitless";
  /// Free metadata (source, fit report): the text of a JSON object.
  std::string metadata_json = "{}";
  /// Optional: the scanned points the spline was fitted to (`tbs fit --keep-points`), so that
  /// error maps can be made from the .tbs alone. Empty, or as many as point_parameters.
  std::vector<Point3> points = {};
  std::vector<Point2> point_parameters = {};  ///< The parameter (u, v) of each point.
  /// The seams that glue the domain's components (charts) into one surface; empty for a
  /// spline over one planar domain.
  Atlas atlas = {};
};

struct ReadOptions {
  /// Reject splines that violate the knot conditions (check_knot_conditions()).
  bool check_knots = true;
};

/// Parses the text of a .tbs file. `name` is used in messages.
/// \throw InvalidInput naming the JSON field (e.g. `domain.triangles[4][2]`) and the problem.
SplineFile parse_tbs(std::string_view text, const std::string& name = "<memory>",
                     const ReadOptions& options = {});

/// Reads a .tbs file. \throw IoError if it cannot be read; InvalidInput as parse_tbs().
SplineFile read_tbs(const std::string& path, const ReadOptions& options = {});

/// The .tbs text of a spline. Numbers round-trip exactly.
/// \throw InvalidInput if the units are unknown, metadata_json is not a JSON object, points
///   and point_parameters differ in size or hold a non-finite value, or the atlas is not well
///   formed (check_atlas_structure()) (the message names no file).
std::string format_tbs(const SplineFile& file);

/// Writes a .tbs file atomically (see AtomicOutput).
/// \throw InvalidInput as format_tbs(), prefixed with `path: `, before any file is touched;
///   IoError if the file cannot be written.
void write_tbs(const std::string& path, const SplineFile& file);

/// Checks, without creating anything, what AtomicOutput checks before it writes `path`: that
/// it names a file (not a directory, nor an existing device, pipe or socket) in a folder that
/// exists. For checking outputs before long work.
/// \throw IoError `cannot write '<path>': <why>`.
void check_output_path(const std::string& path);

/// An output file that appears only when complete: data goes to a temporary file in the same
/// folder, commit() renames it over `path`; destruction without commit() removes it, so a
/// failed or interrupted run never leaves a partial file nor replaces a good one. If `path` is
/// a symbolic link, its target is written (the temporary file goes beside the target) and the
/// link stays.
class AtomicOutput {
 public:
  /// \throw IoError as check_output_path(), or if the temporary file cannot be created.
  explicit AtomicOutput(std::string path);
  ~AtomicOutput();
  AtomicOutput(const AtomicOutput&) = delete;
  AtomicOutput& operator=(const AtomicOutput&) = delete;

  /// Path of the temporary file to write to.
  const std::string& temp_path() const { return temp_; }
  /// Writes `data` as the temporary file's whole content. \throw IoError naming the final path.
  void write(std::string_view data);
  /// Renames the temporary file to the final path. \throw IoError if the rename fails.
  void commit();

 private:
  std::string path_;    // as given, for messages
  std::string target_;  // what commit() replaces: path_, or the file a symbolic link points to
  std::string temp_;
  int slot_ = -1;  // in the registry remove_pending_outputs() reads; -1 if not registered
  bool committed_ = false;
};

/// Makes SIGINT, SIGTERM and SIGHUP remove the temporary files of all live AtomicOutputs and
/// then end the process as the signal would have (the default action is re-raised), so that
/// an interrupted program leaves neither partial files nor temporaries. Meant for programs
/// (the `tbs` command calls it first thing); a program with its own handlers can call
/// remove_pending_outputs() from them instead. Idempotent. Throws no tbs exception.
void remove_outputs_on_signal();

/// Removes the temporary files of all live AtomicOutputs (the final files are untouched).
/// Async-signal-safe: it only reads fixed buffers and calls unlink(). Throws nothing.
void remove_pending_outputs() noexcept;

/// Writes `data` to `path` through an AtomicOutput.
/// \throw IoError if the temporary file cannot be created, written or renamed.
void write_file_atomic(const std::string& path, std::string_view data);

/// `text` with every byte sequence that is not valid UTF-8 replaced by U+FFFD. File names on
/// Linux are bytes; names written into JSON (.tbs metadata, reports, glTF) must be UTF-8.
/// \throw nothing but std::bad_alloc.
std::string valid_utf8(std::string_view text);

/// Reads a whole file. \throw IoError with the path and the system's reason.
std::string read_file(const std::string& path);

}  // namespace tbs
