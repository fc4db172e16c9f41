// sin, cos and tan that give the same bits on every IEEE 754 platform: the protocol has client and server
// derive the same view (make_view's tan) and the same cone test (the criteria's cos and sin), and the
// browser's libm (emscripten's musl) need not round them as glibc does. Each is a Cody-Waite reduction by
// pi/2 and fdlibm's fixed kernel polynomials, evaluated in double with only +, -, *, / and floor, then
// rounded once to float: within an ulp of the exact value for |x| <= 2^19 pi/2 (beyond, still the same
// bits everywhere, with less accuracy). Special cases as C's: NaN and +-inf give NaN, +-0 keeps its sign
// in sin and tan.
// Shared with the browser build: plain arithmetic, single-threaded.
#pragma once

namespace pms {

float portable_sin(float x);
float portable_cos(float x);
float portable_tan(float x);

}  // namespace pms
