#pragma once
// A layer-check fixture: core sits below strategies, so this include must be refused.
#include "strategies/strategy.hpp"
