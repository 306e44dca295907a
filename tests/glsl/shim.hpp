// Just enough GLSL for C++ to compile the shaders of `gonio export`: the
// tests evaluate them on the CPU and compare with the Rust models
// (tests/tests/brdf_export.rs). GLSL_FLOAT is the scalar: double checks the
// translation of the formulas, float the precision a GPU would have.
#pragma once
#include <cmath>
#include <cstdio>

typedef GLSL_FLOAT S;
using std::abs;
using std::cos;
using std::exp;
using std::pow;
using std::sin;
using std::sqrt;

struct vec2 {
    S x, y;
    vec2(S a, S b) : x(a), y(b) {}
};
struct vec3 {
    S x, y, z;
    explicit vec3(S a) : x(a), y(a), z(a) {}
    vec3(S a, S b, S c) : x(a), y(b), z(c) {}
};

inline vec3 operator+(vec3 a, vec3 b) { return vec3(a.x + b.x, a.y + b.y, a.z + b.z); }
inline vec3 operator/(vec3 a, S s) { return vec3(a.x / s, a.y / s, a.z / s); }
inline vec2 operator/(vec2 a, S s) { return vec2(a.x / s, a.y / s); }
inline S dot(vec3 a, vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline S dot(vec2 a, vec2 b) { return a.x * b.x + a.y * b.y; }
inline S length(vec3 a) { return sqrt(dot(a, a)); }
inline S length(vec2 a) { return sqrt(dot(a, a)); }
inline S max(S a, S b) { return a > b ? a : b; }
inline S min(S a, S b) { return a < b ? a : b; }
inline S clamp(S x, S lo, S hi) { return min(max(x, lo), hi); }
inline S atan(S y, S x) { return std::atan2(y, x); }
inline S degrees(S radians) { return radians * S(57.295779513082320876798154814105); }
inline vec3 cross(vec3 a, vec3 b) { return vec3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x); }

// GLSL's `float` is the scalar from here on (the shader and its parameters).
#define float S
