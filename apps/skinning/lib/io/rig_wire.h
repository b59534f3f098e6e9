// SPDX-License-Identifier: MIT
/// \file
/// A rig and its load report as bytes, to pass them from the child process that read the file
/// (io/isolated.h) back to the caller. Same machine, same build: raw little-endian values, no
/// versioning; `decode` checks lengths so a truncated message is an error, not a crash.
#pragma once

#include <string>

#include "isokit/skinning/rig.h"
#include "isokit/skinning/rig_io.h"

namespace isokit::skinning::io {

std::string encode_rig(const Rig& rig, const LoadReport& report);
/// \throw isokit::InputError naming `source` when the bytes are truncated or inconsistent.
void decode_rig(const std::string& bytes, const std::string& source, Rig& rig, LoadReport& report);

}  // namespace isokit::skinning::io
