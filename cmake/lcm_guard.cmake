# cmake -DDIR=<folder of lcm-gen's C++ headers> -P lcm_guard.cmake
# Hardens the decode of lcm-gen 1.3.1's C++ headers against hostile messages (issue 18, found by
# fuzz/harness/lcm_decode.cc): as generated,
#   - a string whose length field is 0 or negative reaches std::string::assign(p, len - 1):
#     std::length_error, or a read past the buffer;
#   - an array count (num_points, size, num_packets ...) is used in vector::resize() BEFORE the
#     bytes are checked: a negative count throws std::length_error, a huge one (2^31 - 1) allocates
#     gigabytes for a 40-byte message.
# An exception there escapes lcm's C dispatch and terminates the process. The guards below make
# decode() return -1 instead, which lcm's typed subscribe reports and skips. An element of a 1-D
# array, a struct or a string takes at least one byte, so a count above the bytes left cannot be
# valid; the rows of a 2-D byte array may be empty (see below).
file(GLOB headers ${DIR}/*.hpp)
foreach(h ${headers})
  file(READ ${h} text)
  string(FIND "${text}" "lanemap-lcm-guard" already)
  if(NOT already EQUAL -1)
    continue()
  endif()
  string(REGEX REPLACE "if\\((__[A-Za-z0-9_]+) > maxlen - pos\\) return -1;"
         "if(\\1 < 1 || \\1 > maxlen - pos) return -1;" text "${text}")
  # A 2-D primitive array (lidar_packets_t.data[num_packets][packet_size]): its rows take
  # packet_size bytes each, which may be 0, so the row count is bounded by bytes / packet_size,
  # or by 65536 rows of nothing (a row is an empty std::vector: 24 bytes).
  string(REGEX REPLACE
         "([ ]*)(this->[A-Za-z0-9_]+)\\.resize\\(this->([A-Za-z0-9_]+)\\);\n([ ]*for \\(int a0 = 0; a0 < this->[A-Za-z0-9_]+; a0\\+\\+\\) {\n[ ]*if\\(this->)([A-Za-z0-9_]+)\\) {"
         "\\1if(this->\\3 < 0 || this->\\5 < 0 || (this->\\5 > 0 ? this->\\3 > (maxlen - pos) / this->\\5 : this->\\3 > 65536)) return -1;\n\\1\\2.resize(static_cast<size_t>(this->\\3));\n\\4\\5) {"
         text "${text}")
  string(REGEX REPLACE "([ ]*)(this->[A-Za-z0-9_]+(\\[[a-z0-9]+\\])*)\\.resize\\(this->([A-Za-z0-9_]+)\\);"
         "\\1if(this->\\4 < 0 || this->\\4 > maxlen - pos) return -1;\n\\1\\2.resize(this->\\4);" text "${text}")
  file(WRITE ${h} "// lanemap-lcm-guard: decode hardened by cmake/lcm_guard.cmake\n${text}")
endforeach()
