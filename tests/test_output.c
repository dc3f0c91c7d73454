#include "test.h"
const test_case test_output_cases[] = { TEST_END };
