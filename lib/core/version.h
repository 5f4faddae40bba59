#pragma once
/// \file version.h
/// The library version at run time; the macros of core/version_macros.h give it at compile time.
#include "core/version_macros.h"

namespace normalflow {
/// The library version, "major.minor.patch" (NORMALFLOW_VERSION_STRING of the build that compiled the library).
const char* version();
}  // namespace normalflow
