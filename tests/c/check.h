/* The C tests' assertion kit lives in tests/check.h (shared with the C FMI hosts). */
#include "../check.h"
