#pragma once
/// Load factors and times as the decimals they stand for, and numbers as messages show them.

#include <string>

namespace depthfem {

/// The double nearest to `value` rounded to 12 significant decimal digits. Load factors and
/// times are sums and multiples of decimal increments (0.28 + 0.16, 3 x 0.1) whose binary
/// round-off would show in the results (0.44000000000000006, 0.30000000000000004); rounded they
/// are the doubles nearest to the decimals (0.44, 0.3), which print as such. The change is below
/// 1e-12 of the value, far below any solver tolerance.
double round_to_decimal(double value);

/// A number in a message, to four significant digits at any scale (std::to_string would print
/// 1.8e-4 as 0.000180 and 1e-9 as 0.000000).
std::string shown(double value);

}  // namespace depthfem
