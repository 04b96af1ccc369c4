// The version of stereodet, as the top-level CMake project() declares it ("0.1.0"); results record
// it.
#ifndef STEREODET_UTIL_VERSION_H_
#define STEREODET_UTIL_VERSION_H_

namespace stereodet {

const char* StereodetVersion();

}  // namespace stereodet

#endif  // STEREODET_UTIL_VERSION_H_
