/* col0rme public API: plain structs in, plain arrays out, status codes. */
#pragma once

#include "core/err.h"
#include "io/tiff.h"
