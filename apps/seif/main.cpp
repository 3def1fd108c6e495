#include "commands.hpp"

int main(int argc, char** argv) { return seif::cli::main(argc, argv); }
