# help2man.awk - the "Engine settings" block of `trajreplay --help` as troff
# .TP entries, for the ENGINE SETTINGS section of trajreplay(1): one source
# (lib/engine/engine_settings.c), so the man page cannot omit an option.
#   trajreplay --help | awk -f daemon/doc/help2man.awk
/^Engine settings/ { on = 1; next }
on && /^$/ { exit }
on && /^  --/ {
    if (tp) print fix(text)
    opt = $1; arg = ""
    rest = substr($0, 3 + length(opt))
    if (match(rest, /^ [^ ][^ ]*/)) { arg = substr(rest, 2, RLENGTH - 1); rest = substr(rest, RLENGTH + 1) }
    sub(/^ +/, "", rest)
    gsub(/-/, "\\-", opt)
    print ".TP"
    print (arg != "" ? ".BI \"" opt " \" " arg : ".B " opt)
    text = rest; tp = 1; next
}
on && tp { line = $0; sub(/^ +/, "", line); text = text " " line }
END { if (tp) print fix(text) }
# (a text line never starts with a troff control character)
function fix(t) { return t ~ /^[.']/ ? "\\&" t : t }
