#pragma once
#include <map>
#include <string>

namespace twistslam {
// Library name -> version string of what the core was compiled and linked against.
std::map<std::string, std::string> build_info();
}  // namespace twistslam
