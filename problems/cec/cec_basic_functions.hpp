#pragma once
// The basic functions of the CEC 2017 and 2022 suites, as the organisers' C code computes them
// (the same operations in the same order, so that values agree with theirs to rounding).
//
// Each takes z, the shifted, scaled and rotated point of length n, and u, the same point before
// the rotation (the C code's global `y`): Schaffer's F7 reads u alone and the Lunacek bi-Rastrigin
// both, as the organisers' code does; the others read z.
namespace mhb::cec {

using BasicFunction = double (*)(const double* z, const double* u, int n);

double bent_cigar(const double* z, const double* u, int n);
double sum_of_different_powers(const double* z, const double* u, int n);
double zakharov(const double* z, const double* u, int n);
double rosenbrock(const double* z, const double* u, int n);  // of z + 1
double rastrigin(const double* z, const double* u, int n);
double schaffer_f7(const double* z, const double* u, int n);  // reads u, not z
// u = 2*sign(o)*0.1*(x - o) before the rotation, z = M u (docs/test-functions.md).
double lunacek_bi_rastrigin(const double* z, const double* u, int n);
double levy_cec2017(const double* z, const double* u, int n);  // w = 1 + (z - 1)/4
double levy_cec2022(const double* z, const double* u, int n);  // w = 1 + z/4
double modified_schwefel(const double* z, const double* u, int n);
double high_conditioned_elliptic(const double* z, const double* u, int n);
double discus(const double* z, const double* u, int n);
double ackley(const double* z, const double* u, int n);
double weierstrass(const double* z, const double* u, int n);
double griewank(const double* z, const double* u, int n);
double katsuura(const double* z, const double* u, int n);
double happycat(const double* z, const double* u, int n);
double hgbat(const double* z, const double* u, int n);
double griewank_rosenbrock(const double* z, const double* u, int n);
double expanded_schaffer_f6(const double* z, const double* u, int n);

}  // namespace mhb::cec
