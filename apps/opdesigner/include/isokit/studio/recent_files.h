// SPDX-License-Identifier: MIT
/// \file
/// The studio's recent-files list: a few spec paths, most recent first, persisted as JSON
/// (`{"recent": ["a.json", ...]}`) so the next session can offer them.
#pragma once

#include <string>
#include <vector>

namespace isokit::studio {

/// `${XDG_CONFIG_HOME}/isokit/recent.json`, or `~/.config/isokit/recent.json` when
/// XDG_CONFIG_HOME is unset or empty ("" when neither it nor HOME is set).
std::string default_recent_files_path();

/// A most-recent-first list of paths, at most `capacity` long, without duplicates.
class RecentFiles {
 public:
  /// Reads `path` if it exists; a missing, unreadable or malformed file gives an empty list (a
  /// broken preferences file must not stop the studio). `path` "" keeps the list in memory only.
  explicit RecentFiles(std::string path, int capacity = 10);

  /// Moves `file` (made absolute) to the front and writes the list (atomically; creating the
  /// folder). A write failure is ignored and reported by `last_error()`.
  void add(const std::string& file);
  /// Drops `file` (e.g. it no longer opens) and writes the list.
  void remove(const std::string& file);
  const std::vector<std::string>& files() const { return files_; }
  const std::string& path() const { return path_; }
  /// The last write error ("" when the last write succeeded).
  const std::string& last_error() const { return last_error_; }

 private:
  void store();
  std::string path_;
  int capacity_;
  std::vector<std::string> files_;
  std::string last_error_;
};

}  // namespace isokit::studio
