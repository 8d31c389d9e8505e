#include "jointlab/tests/test_util.h"
