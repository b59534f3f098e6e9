// SPDX-License-Identifier: MIT
// The analytic operators are inline (analytic.h, shared with CUDA); this unit checks that the
// header compiles on its own.
#include "isokit/operators/analytic.h"
