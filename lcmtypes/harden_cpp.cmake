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
  file(WRITE ${h} "${text}")
endforeach()
