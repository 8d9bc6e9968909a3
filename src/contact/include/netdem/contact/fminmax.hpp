#pragma once
// fmax and fmin without the library call. On x86-64 GCC does not inline std::fmax/std::fmin (their
// NaN rule), so each is a call into libm, which in a force loop clobbers every vector register and
// forces spills. These give the same bits as Debian 12's glibc for every pair of arguments but the
// two zeros of opposite sign (equal ones give the first argument; a NaN argument yields the other
// one; tested in test_contact FMinMax.SameBitsAsTheLibrary), as a compare and a select. For
// (+0, -0) and (-0, +0) glibc returns its second argument while these return the first; an
// optimising GCC treats fmax and fmin as commutative there, so "the library's zero" depends on the
// optimisation level (IEEE 754 allows either zero).
namespace netdem::contact {

/// std::fmax(a, b): a if a >= b or b is a NaN, else b.
constexpr double fmax_of(double a, double b) { return (a >= b || b != b) ? a : b; }
/// std::fmin(a, b): a if a <= b or b is a NaN, else b.
constexpr double fmin_of(double a, double b) { return (a <= b || b != b) ? a : b; }

static_assert(fmax_of(1.0, 2.0) == 2.0 && fmax_of(2.0, 1.0) == 2.0 && fmin_of(1.0, 2.0) == 1.0);

}  // namespace netdem::contact
