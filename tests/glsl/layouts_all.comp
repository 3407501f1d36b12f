#version 450
// Every std430 struct of common/kernels/layouts.h in a buffer of its own, so that glslang gives each
// its std430 offsets and array stride; tests/test_layouts.cpp compares them with the C++ side.
#extension GL_GOOGLE_include_directive : require
layout(local_size_x = 1) in;
#include "kernels/layouts.h"
layout(std430, binding = 0) buffer BufferRay { Ray vRay[]; };
layout(std430, binding = 1) buffer BufferHit { Hit vHit[]; };
layout(std430, binding = 2) buffer BufferBvhNode { BvhNode vBvhNode[]; };
layout(std430, binding = 3) buffer BufferTriangle { Triangle vTriangle[]; };
layout(std430, binding = 4) buffer BufferInstanceRecord { InstanceRecord vInstanceRecord[]; };
layout(std430, binding = 5) buffer BufferLsNode { LsNode vLsNode[]; };
layout(std430, binding = 19) buffer BufferLsRecord { LsRecord vLsRecord[]; };
layout(std430, binding = 6) buffer BufferLsCounters { LsCounters vLsCounters[]; };
layout(std430, binding = 7) buffer BufferTraceWork { TraceWork vTraceWork[]; };
layout(std430, binding = 8) buffer BufferCameraFrame { CameraFrame vCameraFrame[]; };
layout(std430, binding = 9) buffer BufferShadeInstance { ShadeInstance vShadeInstance[]; };
layout(std430, binding = 10) buffer BufferShadeVertex { ShadeVertex vShadeVertex[]; };
layout(std430, binding = 11) buffer BufferShadeTriangle { ShadeTriangle vShadeTriangle[]; };
layout(std430, binding = 12) buffer BufferShadeMaterial { ShadeMaterial vShadeMaterial[]; };
layout(std430, binding = 13) buffer BufferShadeLight { ShadeLight vShadeLight[]; };
layout(std430, binding = 14) buffer BufferShadeParams { ShadeParams vShadeParams[]; };
layout(std430, binding = 15) buffer BufferPathState { PathState vPathState[]; };
layout(std430, binding = 16) buffer BufferShaderParams { ShaderParams vShaderParams[]; };
layout(std430, binding = 17) buffer BufferShadePush { ShadePush vShadePush[]; };
layout(std430, binding = 18) buffer BufferShadeConstants { ShadeConstants vShadeConstants[]; };
void main() {}
