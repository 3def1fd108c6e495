#include <seif/io/dataset.hpp>
