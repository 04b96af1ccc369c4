#include "stereodet/util/version.h"

namespace stereodet {

// STEREODET_VERSION comes from CMake (util/CMakeLists.txt), for this file only, so that a new
// version recompiles one file.
const char* StereodetVersion() { return STEREODET_VERSION; }

}  // namespace stereodet
