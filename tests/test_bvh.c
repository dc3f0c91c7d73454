#include "test.h"
const test_case test_bvh_cases[] = { TEST_END };
