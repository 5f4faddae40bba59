#pragma once
// What `normalflow --version` says: the version, the adapters this build of the tool links, and the licence
// that follows from them (normalflow's own code is Apache-2.0; CGAL makes the tool GPL-3.0-or-later, TetGen
// AGPL-3.0-or-later).
#include <string>

namespace normalflow::cli {

/// The text of --version: "normalflow 0.2.0", then one line per third-party library linked (name, licence,
/// what it is for), then the licence of this build of the tool and why.
std::string version_text();

}  // namespace normalflow::cli
