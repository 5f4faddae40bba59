#include "core/version.h"

namespace normalflow {
const char* version() { return NORMALFLOW_VERSION_STRING; }
}  // namespace normalflow
