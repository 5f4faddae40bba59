# bash completion of normalflow: subcommands, each subcommand's flags, the choices of a flag that has them
# (--mode bilateral|guided|...), and file names otherwise. It asks the tool itself (`normalflow [CMD] --help-all`),
# so it always matches the installed version. Installed as share/bash-completion/completions/normalflow.
_normalflow() {
    local cur=${COMP_WORDS[COMP_CWORD]} prev=${COMP_WORDS[COMP_CWORD-1]} tool=${COMP_WORDS[0]}
    local cmd="" i
    for ((i = 1; i < COMP_CWORD; i++)); do
        case ${COMP_WORDS[i]} in -*) ;; *) cmd=${COMP_WORDS[i]}; break ;; esac
    done
    COMPREPLY=()
    if [[ -z $cmd ]]; then
        if [[ $cur == -* ]]; then
            mapfile -t COMPREPLY < <(compgen -W "--help --version" -- "$cur")
        else
            local cmds
            cmds=$("$tool" --help 2>/dev/null | sed -n '/^Subcommands:/,$ s/^  \([a-z][a-z]*\)  .*/\1/p')
            mapfile -t COMPREPLY < <(compgen -W "$cmds" -- "$cur")
        fi
        return
    fi
    local help
    help=$("$tool" "$cmd" --help-all 2>/dev/null) || return
    if [[ $prev == --* ]]; then
        # the flag's line: "  --mode auto|keep|remesh  help" (choices), "  --iterations INT|auto ..." (a value or
        # a word) or "  --shell FLOAT ..." (a value)
        local spec
        spec=$(printf '%s\n' "$help" | sed -n "s/^  \(-[a-zA-Z],\)\{0,1\}${prev}\( \([^ ]*\)\)\{0,1\}.*/\3/p" | head -n 1)
        spec=${spec%%=*}  # "auto|keep|remesh=auto": the default after '='
        if [[ $spec == *"|"* ]]; then
            # the words; a value's type (INT|auto, SIZE|auto) offers only its word
            local words
            words=$(printf '%s\n' ${spec//|/ } | grep -v '^[A-Z]*$')
            mapfile -t COMPREPLY < <(compgen -W "$words" -- "$cur")
            return
        elif [[ -n $spec && $spec != FILE && $spec != TEXT ]]; then
            return  # a number or a size: nothing to offer
        fi
    fi
    if [[ $cur == -* ]]; then
        local flags
        flags=$(printf '%s\n' "$help" | grep -o -- '--[a-z][a-z0-9-]*' | sort -u)
        mapfile -t COMPREPLY < <(compgen -W "$flags" -- "$cur")
    else
        mapfile -t COMPREPLY < <(compgen -f -- "$cur")
        compopt -o filenames 2>/dev/null
    fi
}
complete -F _normalflow normalflow
