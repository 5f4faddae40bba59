#pragma once
/// \file cgal_info.h
namespace normalflow {
/// The CGAL version this build links, e.g. "5.5.1".
const char* cgal_version();
}  // namespace normalflow
