# Sourced by the benchmark scripts. parse_options "NAME ..." "$@" sets, for each "--NAME VALUE"
# pair of the arguments, the variable NAME (dashes as underscores: --grid-size sets grid_size);
# anything else prints $usage and exits 2.
parse_options() {
  local names=" $1 " name
  shift
  while [ $# -ge 2 ] && [[ "$1" == --* ]] && [[ "$names" == *" ${1#--} "* ]]; do
    name="${1#--}"
    printf -v "${name//-/_}" '%s' "$2"
    shift 2
  done
  [ $# -eq 0 ] || { echo "$usage" >&2; exit 2; }
}
