#include "test.h"
const test_case test_materials_cases[] = { TEST_END };
