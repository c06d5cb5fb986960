#pragma once
// A layer-check fixture: strategies may include core.
#include "core/elasticity.hpp"
