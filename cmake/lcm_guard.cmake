# cmake -DDIR=<folder of lcm-gen's C++ headers> -P lcm_guard.cmake
# Hardens the decode of lcm-gen 1.3.1's C++ headers against hostile messages (issue 18, found by
# fuzz/harness/lcm_decode.cc): as generated,
#   - a string whose length field is 0 or negative reaches std::string::assign(p, len - 1):
#     std::length_error, or a read past the buffer;
#   - an array count (num_points, size, num_packets ...) is used in vector::resize() BEFORE the
#     bytes are checked: a negative count throws std::length_error, a huge one (2^31 - 1) allocates
#     gigabytes for a 40-byte message.
# An exception there escapes lcm's C dispatch and terminates the process. The guards below make
# decode() return -1 instead, which lcm's typed subscribe reports and skips. Every array element
# of our types takes at least one byte, so a count above the bytes left cannot be valid.
file(GLOB headers ${DIR}/*.hpp)
foreach(h ${headers})
  file(READ ${h} text)
  string(FIND "${text}" "lanemap-lcm-guard" already)
  if(NOT already EQUAL -1)
    continue()
  endif()
  string(REGEX REPLACE "if\\((__[A-Za-z0-9_]+) > maxlen - pos\\) return -1;"
         "if(\\1 < 1 || \\1 > maxlen - pos) return -1;" text "${text}")
  string(REGEX REPLACE "([ ]*)(this->[A-Za-z0-9_]+(\\[[a-z0-9]+\\])*)\\.resize\\(this->([A-Za-z0-9_]+)\\);"
         "\\1if(this->\\4 < 0 || this->\\4 > maxlen - pos) return -1;\n\\1\\2.resize(this->\\4);" text "${text}")
  file(WRITE ${h} "// lanemap-lcm-guard: decode hardened by cmake/lcm_guard.cmake\n${text}")
endforeach()
