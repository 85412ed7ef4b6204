#include <iostream>

#include "cli.h"

int main(int argc, char** argv) { return handeye::cli::run(argc, argv, std::cout, std::cerr); }
