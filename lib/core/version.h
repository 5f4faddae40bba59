#pragma once
/// \file version.h
namespace normalflow {
/// The library version, "major.minor.patch".
const char* version();
}  // namespace normalflow
