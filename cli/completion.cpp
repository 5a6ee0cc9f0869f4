#include "cli/completion.h"

#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <CLI/CLI.hpp>

namespace scanplan::cli {

namespace {

// One case of the script: the command path ("plan", "job show"), the words that complete after
// it (subcommands, options) and the options that take a value (a file name or a number follows).
struct CommandWords {
  std::string path;
  std::vector<std::string> words;
  std::vector<std::string> valued;
  bool needs_subcommand = false;  // no file argument here: a subcommand must follow
};

void collect(CLI::App& app, const std::string& path, std::vector<CommandWords>& out) {
  CommandWords c{path, {}, {}, app.get_require_subcommand_min() > 0};
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
    c.words.push_back(sub->get_name());
  }
  for (const CLI::Option* o : app.get_options()) {
    if (!o->nonpositional()) continue;
    for (const std::string& n : o->get_lnames()) {
      c.words.push_back("--" + n);
      if (o->get_items_expected_min() > 0) c.valued.push_back("--" + n);
    }
    for (const std::string& n : o->get_snames()) {
      if (o->get_items_expected_min() > 0) c.valued.push_back("-" + n);
    }
  }
  out.push_back(c);
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
    collect(*sub, path.empty() ? sub->get_name() : path + " " + sub->get_name(), out);
  }
}

std::string bashScript(CLI::App& app) {
  std::vector<CommandWords> commands;
  collect(app, "", commands);
  std::string cases;
  for (const CommandWords& c : commands) {
    cases +=
        fmt::format("    '{}') words='{}'; valued=' {} '; need={} ;;\n", c.path,
                    fmt::join(c.words, " "), fmt::join(c.valued, " "), c.needs_subcommand ? 1 : 0);
  }
  return fmt::format(R"(# scanplan completion for bash (and zsh, through bashcompinit).
# Load it in the shell:           source <(scanplan completion bash)
# or install it for every shell:  scanplan completion bash > ~/.local/share/bash-completion/completions/scanplan
_scanplan() {{
  local cur prev path word words valued need i
  cur="${{COMP_WORDS[COMP_CWORD]}}"
  prev="${{COMP_WORDS[COMP_CWORD-1]}}"
  # The command path: the leading words that name commands and subcommands.
  path=''
  for ((i = 1; i < COMP_CWORD; i++)); do
    word="${{COMP_WORDS[i]}}"
    case "$word" in -*) continue ;; esac
    _scanplan_words "$path"
    case " $words " in
      *" $word "*) path="${{path:+$path }}$word" ;;
    esac
  done
  _scanplan_words "$path"
  case "$valued" in
    *" $prev "*) COMPREPLY=($(compgen -f -- "$cur")); return ;;
  esac
  local subs='' opts='' w
  for w in $words; do
    case "$w" in -*) opts="$opts $w" ;; *) subs="$subs $w" ;; esac
  done
  if [[ "$cur" == -* ]]; then
    COMPREPLY=($(compgen -W "$opts" -- "$cur"))
  elif [ "$need" = 1 ]; then
    COMPREPLY=($(compgen -W "$subs" -- "$cur"))
  else
    COMPREPLY=($(compgen -W "$subs" -- "$cur") $(compgen -f -- "$cur"))
  fi
  return 0
}}
_scanplan_words() {{
  case "$1" in
{}    *) words=''; valued=''; need=0 ;;
  esac
}}
complete -o filenames -F _scanplan scanplan
)",
                     cases);
}

}  // namespace

std::string completionScript(CLI::App& app, const std::string& shell) {
  if (shell == "zsh") {
    return "# scanplan completion for zsh: bash's, through zsh's bashcompinit.\n"
           "# Load it in the shell: source <(scanplan completion zsh)\n"
           "autoload -U +X compinit && compinit\n"
           "autoload -U +X bashcompinit && bashcompinit\n" +
           bashScript(app);
  }
  return bashScript(app);
}

}  // namespace scanplan::cli
