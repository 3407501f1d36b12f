#version 450
// The layout check's own test: a struct whose C++ and std430 layouts differ (planted_layout.h).
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 1) in;
#include "planted_layout.h"
layout(std430, binding = 0) buffer BufferPlanted { Planted vPlanted[]; };
void main() {}
