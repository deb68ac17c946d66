"""Shell completion scripts generated from the ``zendock`` argparse parser (``zendock completion bash|zsh``).

One source, generated views: :func:`command_tree` reads the parser (subcommands, options, the choices of
options that have them) into a :class:`Command` tree; :func:`bash_script` and :func:`zsh_script` render it.
Both scripts find where the words typed so far lead in the tree (each word that names a subcommand of
the current command goes one level down), then offer that command's subcommands, or its options after a
``-``, or an option's choices after the option; anything else falls back to file names. Pure: no bus.
"""

from __future__ import annotations

import argparse
import re
from dataclasses import dataclass, field


@dataclass(frozen=True)
class Option:
    flags: tuple[str, ...]
    help: str = ""
    takes_value: bool = False
    choices: tuple[str, ...] = ()


@dataclass
class Command:
    """A parser: its path of subcommand names from the top (``("keys", "list")``), options, subcommands."""

    path: tuple[str, ...]
    help: str = ""
    options: list[Option] = field(default_factory=list)
    subcommands: dict[str, Command] = field(default_factory=dict)
    #: Choices of its positional arguments (``completion bash|zsh``), offered where a subcommand would be.
    positional_choices: list[str] = field(default_factory=list)

    @property
    def words(self) -> list[str]:
        return [*self.subcommands, *self.positional_choices]

    def walk(self) -> list[Command]:
        """This command and every command below it, depth first."""
        found = [self]
        for sub in self.subcommands.values():
            found += sub.walk()
        return found


def _help_text(text: str | None, action: argparse.Action | None = None) -> str:
    """One line of help, with argparse's ``%(default)s``-style fields filled in as ``--help`` fills them."""
    if not text or text == argparse.SUPPRESS:
        return ""
    if action is not None and "%" in text:
        try:
            text = text % {**vars(action), "default": action.default}
        except (KeyError, TypeError, ValueError):
            pass
    return " ".join(text.split())


def command_tree(parser: argparse.ArgumentParser, path: tuple[str, ...] = (), help_text: str = "") -> Command:
    """The parser's subcommands and options as a :class:`Command` tree."""
    command = Command(path, help_text)
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {choice.dest: _help_text(choice.help) for choice in action._choices_actions}
            for name, sub in action.choices.items():
                command.subcommands[name] = command_tree(sub, (*path, name), helps.get(name, ""))
        elif not action.option_strings and action.choices:
            command.positional_choices += [str(c) for c in action.choices]
        elif action.option_strings and action.help != argparse.SUPPRESS:
            choices = tuple(str(c) for c in action.choices) if action.choices else ()
            command.options.append(
                Option(
                    tuple(action.option_strings),
                    _help_text(action.help, action),
                    takes_value=action.nargs != 0,
                    choices=choices,
                )
            )
    return command


def _words(items: list[str]) -> str:
    return " ".join(items)


def bash_script(tree: Command, prog: str = "zendock") -> str:
    """A bash completion script: ``source <(zendock completion bash)``."""
    fn = "_" + re.sub(r"\W", "_", prog)
    subs, words, opts, values = [], [], [], []
    for command in tree.walk():
        key = " ".join(command.path)
        if command.subcommands:
            subs.append(f'        "{key}") echo "{_words(list(command.subcommands))}" ;;')
        if command.words:
            words.append(f'        "{key}") echo "{_words(command.words)}" ;;')
        flags = [flag for option in command.options for flag in option.flags]
        opts.append(f'        "{key}") echo "{_words(flags)}" ;;')
        for option in command.options:
            if option.takes_value:
                shown = _words(list(option.choices)) if option.choices else "__value__"
                patterns = "|".join(f'"{" ".join((*command.path, flag))}"' for flag in option.flags)
                values.append(f'        {patterns}) echo "{shown}" ;;')
    nl = "\n"
    return f"""# bash completion for {prog}, generated from its argparse parser by `{prog} completion bash`.
# Load it with:  source <({prog} completion bash)

{fn}_subcommands() {{
    case "$1" in
{nl.join(subs)}
    esac
}}

{fn}_words() {{
    case "$1" in
{nl.join(words)}
    esac
}}

{fn}_options() {{
    case "$1" in
{nl.join(opts)}
    esac
}}

{fn}_option_values() {{
    case "$1" in
{nl.join(values)}
    esac
}}

{fn}() {{
    local cur="${{COMP_WORDS[COMP_CWORD]}}" prev="" path="" word i subs values
    (( COMP_CWORD > 1 )) && prev="${{COMP_WORDS[COMP_CWORD-1]}}"
    for (( i = 1; i < COMP_CWORD; i++ )); do
        word="${{COMP_WORDS[i]}}"
        subs=" $({fn}_subcommands "$path") "
        if [[ "$word" != -* && "$subs" == *" $word "* ]]; then
            path="${{path:+$path }}$word"
        fi
    done
    COMPREPLY=()
    if [[ -n "$prev" && "$prev" == -* ]]; then
        values="$({fn}_option_values "${{path:+$path }}$prev")"
        if [[ "$values" == "__value__" ]]; then
            return 0
        elif [[ -n "$values" ]]; then
            COMPREPLY=( $(compgen -W "$values" -- "$cur") )
            return 0
        fi
    fi
    if [[ "$cur" == -* ]]; then
        COMPREPLY=( $(compgen -W "$({fn}_options "$path")" -- "$cur") )
    else
        COMPREPLY=( $(compgen -W "$({fn}_words "$path")" -- "$cur") )
    fi
    return 0
}}

complete -o bashdefault -o default -F {fn} {prog}
"""


def _zsh_quote(text: str) -> str:
    return "'" + text.replace("'", "'\\''") + "'"


def _zsh_escape_colon(text: str) -> str:
    """``_describe`` splits a name from its help at the first unescaped colon."""
    return text.replace(":", "\\:")


def zsh_script(tree: Command, prog: str = "zendock") -> str:
    """A zsh completion script with each subcommand's and option's help: ``source <(zendock completion zsh)``."""
    fn = "_" + re.sub(r"\W", "_", prog)

    def described(name: str, help_text: str) -> str:
        return _zsh_quote(f"{_zsh_escape_colon(name)}:{help_text}" if help_text else _zsh_escape_colon(name))

    subs, words, opts, values = [], [], [], []
    for command in tree.walk():
        key = _zsh_quote(" ".join(command.path))
        if command.subcommands:
            subs.append(
                f"        {key}) reply=( {' '.join(_zsh_quote(name) for name in command.subcommands)} ) ;;"
            )
        if command.words:
            items = [
                described(name, command.subcommands[name].help if name in command.subcommands else "")
                for name in command.words
            ]
            words.append(f"        {key}) reply=( {' '.join(items)} ) ;;")
        items = [described(flag, option.help) for option in command.options for flag in option.flags]
        opts.append(f"        {key}) reply=( {' '.join(items)} ) ;;")
        for option in command.options:
            if option.takes_value:
                shown = " ".join(_zsh_quote(c) for c in option.choices) if option.choices else "__value__"
                patterns = "|".join(_zsh_quote(" ".join((*command.path, flag))) for flag in option.flags)
                values.append(f"        {patterns}) reply=( {shown} ) ;;")
    nl = "\n"
    return f"""#compdef {prog}
# zsh completion for {prog}, generated from its argparse parser by `{prog} completion zsh`.
# Load it with:  source <({prog} completion zsh)   (or save it as _{prog} in a directory of $fpath)

{fn}_subcommands() {{
    reply=()
    case "$1" in
{nl.join(subs)}
    esac
}}

{fn}_words() {{
    reply=()
    case "$1" in
{nl.join(words)}
    esac
}}

{fn}_options() {{
    reply=()
    case "$1" in
{nl.join(opts)}
    esac
}}

{fn}_option_values() {{
    reply=()
    case "$1" in
{nl.join(values)}
    esac
}}

{fn}() {{
    local path_="" word i prev=""
    local -a reply
    for (( i = 2; i < CURRENT; i++ )); do
        word="${{words[i]}}"
        {fn}_subcommands "$path_"
        if [[ "$word" != -* && ${{reply[(Ie)$word]}} -gt 0 ]]; then
            path_="${{path_:+$path_ }}$word"
        fi
    done
    (( CURRENT > 2 )) && prev="${{words[CURRENT-1]}}"
    if [[ "$prev" == -* ]]; then
        {fn}_option_values "${{path_:+$path_ }}$prev"
        if [[ "${{reply[1]}}" == "__value__" ]]; then
            _files
            return
        elif (( ${{#reply}} )); then
            compadd -- "${{reply[@]}}"
            return
        fi
    fi
    if [[ "${{words[CURRENT]}}" == -* ]]; then
        {fn}_options "$path_"
        _describe -t options 'option' reply
    else
        {fn}_words "$path_"
        if (( ${{#reply}} )); then
            _describe -t commands 'command' reply
        else
            _files
        fi
    fi
}}

if [[ "$funcstack[1]" == "{fn}" ]]; then
    {fn} "$@"
else
    compdef {fn} {prog}
fi
"""
