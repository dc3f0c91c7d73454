#include "test.h"
const test_case test_render_cases[] = { TEST_END };
