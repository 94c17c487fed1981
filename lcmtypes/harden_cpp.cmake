# Hardens the C++ bindings that lcm-gen made: before a variable-length array is resized
# to the length a message claims, check that the claim fits in the bytes that are left
# (every element takes at least one byte). Without this, a corrupt length of 2^31 makes
# decode() allocate and construct billions of elements: a hang from one bad datagram.
# Run as: cmake -DDIR=<folder of generated .hpp> -P harden_cpp.cmake
file(GLOB headers ${DIR}/*.hpp)
foreach(h ${headers})
  file(READ ${h} text)
  string(REGEX REPLACE
    "this->([A-Za-z0-9_]+(\\[a[0-9]+\\])*)\\.resize\\(this->([A-Za-z0-9_]+)\\);"
    "if (this->\\3 < 0 || this->\\3 > maxlen - pos) return -1;\n        this->\\1.resize(this->\\3);"
    text "${text}")
  # A string's length must count its terminating NUL (at least 1: a negative or zero one
  # made assign() read far outside the buffer: SIGSEGV), end on that NUL and hold no other:
  # LCM's encoder writes strings up to their first NUL, so a string holding one would be
  # re-encoded into a message no one can decode.
  string(REGEX REPLACE
    "if\\(__([A-Za-z0-9_]+)_len__ > maxlen - pos\\) return -1;"
    "if (__\\1_len__ < 1 || __\\1_len__ > maxlen - pos ||\n        static_cast<const char*>(buf)[offset + pos + __\\1_len__ - 1] != '\\\\0' ||\n        ::memchr(static_cast<const char*>(buf) + offset + pos, 0, static_cast<size_t>(__\\1_len__ - 1)) != nullptr)\n      return -1;"
    text "${text}")
  string(REPLACE  # the same for each string of an array of strings
    "if(__elem_len > maxlen - pos) return -1;"
    "if (__elem_len < 1 || __elem_len > maxlen - pos ||\n            static_cast<const char*>(buf)[offset + pos + __elem_len - 1] != '\\0' ||\n            ::memchr(static_cast<const char*>(buf) + offset + pos, 0, static_cast<size_t>(__elem_len - 1)) != nullptr)\n          return -1;"
    text "${text}")
  file(WRITE ${h} "${text}")
endforeach()
