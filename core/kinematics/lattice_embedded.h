// The control sets shipped in data/lattices/, compiled into pathd::core by
// core/kinematics/embed_lattices.cmake (the generated lattice_embedded.cc):
// a set is found by name wherever the binary runs. Internal to
// core/kinematics/lattice.cc.
#ifndef PATHD_CORE_KINEMATICS_LATTICE_EMBEDDED_H_
#define PATHD_CORE_KINEMATICS_LATTICE_EMBEDDED_H_

#include <string_view>
#include <utility>
#include <vector>

namespace pathd {

// (name, file text) of every data/lattices/<name>.json, sorted by name.
const std::vector<std::pair<std::string_view, std::string_view>>& EmbeddedControlSets();

}  // namespace pathd

#endif  // PATHD_CORE_KINEMATICS_LATTICE_EMBEDDED_H_
