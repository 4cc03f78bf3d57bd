// The voca executable counts its operator new calls (`voca bench soak` reports them per frame); a
// relaxed atomic increment per allocation, on paths that allocate only at start-up.

#include "platform/memory/counting_operator_new.h"
