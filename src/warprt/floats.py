"""Float32 rounding, in the notation of pbrt-v4's "Floating-Point Arithmetic" (section 6.8):
the unit roundoff and gamma(n), the bound on n successive roundings."""

EPS32 = 2.0**-24  # half an ulp of 1.0 in float32


def gamma(n: int) -> float:
    """gamma(n) = n eps / (1 - n eps): a value after n roundings is within gamma(n) of the exact one."""
    return n * EPS32 / (1.0 - n * EPS32)
