#include "io/cgal/cgal_info.h"

#include <CGAL/version.h>

namespace normalflow {
const char* cgal_version() { return CGAL_VERSION_STR; }
}  // namespace normalflow
