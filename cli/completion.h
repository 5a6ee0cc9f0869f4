#pragma once
// Shell completion for scanplan, generated from its argument parser: `scanplan completion bash`
// (or zsh, through zsh's bashcompinit) prints a script that completes commands, subcommands and
// options, and file names where an option or argument takes a value.

#include <string>

namespace CLI {
class App;
}

namespace scanplan::cli {

/// The completion script for `shell` ("bash" or "zsh") of `app`'s commands and options.
std::string completionScript(CLI::App& app, const std::string& shell);

}  // namespace scanplan::cli
