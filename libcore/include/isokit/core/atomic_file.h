// SPDX-License-Identifier: MIT
/// \file
/// Atomic file writing, the one implementation every isokit writer uses: the contents go to a
/// temporary file in the target's folder (hidden, `.<stem>.tmp-<pid>-<counter><extension>`), which
/// is renamed over the target only once it is complete. A reader sees either the old file or the
/// new one, never a partial file; on every failure (the writer throws, a write or the rename
/// fails) the temporary file is removed and an existing target is left unchanged. No fsync: this
/// guards against failed writes and interrupted programs, not against a power loss.
#pragma once

#include <cstddef>
#include <functional>
#include <iosfwd>
#include <string>

namespace isokit {

/// Writes `path` by calling `writer(temp_path)`, which must create and fill the file
/// `temp_path` (for writers that need a file name: Cairo, OpenMesh). The temporary name keeps the
/// target's extension, so writers that choose the format by extension work unchanged.
/// \throw isokit::InputError naming `path` if its folder does not exist, `path` is a folder, the
/// writer created no file or the rename fails; exceptions of `writer` propagate unchanged. In
/// every case the temporary file is removed.
void write_file_atomically(const std::string& path,
                           const std::function<void(const std::string& temp_path)>& writer);

/// Writes `path` from a binary output stream filled by `write` (e.g. a GLB in several parts).
/// \throw isokit::InputError naming `path` if the temporary file cannot be created or a write
/// fails (disk full), and as `write_file_atomically`.
void write_stream_atomically(const std::string& path, const std::function<void(std::ostream& out)>& write);

/// Writes `size` bytes at `data` to `path`. \throw isokit::InputError as `write_stream_atomically`.
void write_bytes_atomically(const std::string& path, const void* data, std::size_t size);

/// Writes `contents` to `path` byte for byte (no newline conversion).
/// \throw isokit::InputError as `write_stream_atomically`.
void write_text_file_atomically(const std::string& path, const std::string& contents);

/// Creates the folder `dir` and its parents when missing (an output folder named on a command
/// line), so that a long run does not fail at its first write. `what` names the option in the
/// error. \throw isokit::InputError naming `what` and `dir` if it cannot be created or is a file.
void make_output_folder(const std::string& dir, const std::string& what);

}  // namespace isokit
