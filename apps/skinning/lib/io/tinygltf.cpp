// SPDX-License-Identifier: MIT
// tinygltf's implementation (the header of Debian's libtinygltf-dev), compiled once with the
// configuration of io/gltf_io.h.
#define TINYGLTF_IMPLEMENTATION
#include "io/gltf_io.h"
