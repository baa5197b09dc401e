#pragma once
// The oracle's dumps, in one include: the format (peelcd/oracle/format.h), its images
// (peelcd/oracle/images.h) and the comparison of two dumps (peelcd/oracle/compare.h).
#include "peelcd/oracle/compare.h"
#include "peelcd/oracle/format.h"
#include "peelcd/oracle/images.h"
