// SPDX-License-Identifier: MIT
/// \file
/// The memory budget of one file load (docs/fuzzing.md, "Memory budget"). Every reader of user
/// files treats the file as hostile: it checks each size the file declares against the bytes that
/// back it before allocating, and charges what it decodes to a `LoadBudget`, so that a small file
/// cannot make a load take more than a fixed multiple of its size — neither by one huge declared
/// count nor by referencing the same data many times.
#pragma once

#include <cstdint>
#include <string>

#include "isokit/core/error.h"

namespace isokit {

/// What one load may take: `kBytesPerInputByte` × the input's bytes + `kFixedBytes`.
/// The input is the file and the files it references (a .gltf's buffers).
struct LoadBudgetRule {
  /// Bytes a load may decode per byte of input. 64: a glTF float decodes to a double (2×), an
  /// unsigned byte joint index to a double (8×), and the loader reads each accessor up to three
  /// times (checks, scene, rig); the rest is margin. Measured on the real rigs: 4–6×.
  static constexpr std::uint64_t kBytesPerInputByte = 64;
  /// Bytes every load may take whatever its size (64 MiB): small files with a valid clip, a mesh
  /// without index buffer, the libraries' own tables.
  static constexpr std::uint64_t kFixedBytes = std::uint64_t{64} << 20;
};

/// The budget of a load of `input_bytes` (saturating: never overflows).
std::uint64_t load_budget_bytes(std::uint64_t input_bytes);

/// The running account of one load: readers `charge` the bytes they are about to allocate from a
/// size the file declared; passing the budget throws an `InputError` naming the file, the item and
/// the size it declared.
class LoadBudget {
 public:
  /// `file`: named in errors; `input_bytes`: the size of the input (the file and what it references).
  LoadBudget(std::string file, std::uint64_t input_bytes);

  /// Adds `bytes` (what `item` declares) to the account.
  /// \throw InputError "<file>: <item>: declares <bytes> bytes, past the load budget ..." when the
  /// total passes `limit()`.
  void charge(std::uint64_t bytes, const std::string& item);
  /// `count` × `element_bytes` with the overflow check, then `charge`.
  void charge(std::uint64_t count, std::uint64_t element_bytes, const std::string& item);
  /// Adds to the input (a buffer the file references, read after the file).
  void add_input(std::uint64_t bytes);

  std::uint64_t limit() const { return load_budget_bytes(input_); }
  std::uint64_t used() const { return used_; }
  std::uint64_t input_bytes() const { return input_; }
  const std::string& file() const { return file_; }

 private:
  std::string file_;
  std::uint64_t input_{0};
  std::uint64_t used_{0};
};

}  // namespace isokit
