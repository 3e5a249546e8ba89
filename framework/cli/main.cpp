#include "framework/cli/commands.hpp"

int main(int argc, char** argv) { return mhb::cli::run(argc, argv); }
