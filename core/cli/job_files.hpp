// The formats of the job files `dqjulia farm` writes, each written for the parser that reads it,
// so that no name or path can change the job or add a command: a value is quoted for its reader
// or, where the format cannot carry it, refused with a ParamError (exit 2) that names the
// character and the flag, before anything is written.
//
// SlurmScript: an sbatch batch script. Two programs read it.
//   sbatch reads the `#SBATCH` lines before the first command (Slurm 22.05, src/sbatch/opt.c:
//   next_line, get_argument). A line ends at LF only, and a NUL ends it early. get_argument
//   splits the line into arguments at unquoted white space (isspace), ends it at an unquoted
//   `#` (a comment), takes '...' and "..." as quotes, and a backslash escapes the next
//   character, inside quotes as well; an argument starting with `:` or the word hetjob means
//   something else. So a value in double quotes with `\` and `"` escaped by a backslash reads
//   back exactly, for every byte but LF and NUL; those are refused.
//   slurmctld keeps a job name of at most 1024 bytes and an --output of at most 4096
//   (MAXPATHLEN; _test_job_desc_fields in src/slurmctld/job_mgr.c).
//   slurmstepd makes the log's name from --output (fname_create in src/slurmd/common/fname.c):
//   `%A`, `%a`, `%j`, ... are patterns and `%%` is a `%`; a backslash anywhere turns every
//   pattern off and is dropped. So a literal `%` is doubled, and a backslash is refused in a
//   log name that holds patterns.
//   bash runs the rest: a comment ends at LF, and a word in single quotes carries every byte
//   but NUL (a `'` as '\'').
// OpenJD: an Open Job Description template (jobtemplate-2023-09) is JSON written by
//   nlohmann::json (every string escaped; the text must be UTF-8). Its `name`, command and args
//   are format strings, where `{{` starts an expression and nothing escapes it, so every name and
//   path goes into a job parameter's value (any characters, at most 1024) and the format
//   strings name the parameter. The job's name, once resolved, must have 1 to 128 characters
//   and none of Unicode's Cc category (U+0000-U+001F, U+007F-U+009F).
// Cost: the text of the file.
#pragma once

#include <string>
#include <string_view>

namespace dqj::cli {

/// `text` in single quotes for sh (every byte but NUL).
std::string shellWord(std::string_view text);

class SlurmScript {
public:
    /// Starts the script with its #! line.
    SlurmScript();
    /// "# text": a comment line for people (line breaks become spaces).
    void comment(std::string_view text);
    /// "#SBATCH --option=value": `value` quoted for sbatch where it needs it. Throws ParamError
    /// naming `flag` for a value sbatch cannot carry (LF, NUL).
    void directive(std::string_view option, std::string_view value, std::string_view flag);
    /// "#SBATCH argument": one argument of sbatch's, given by the user (--sbatch). Throws ParamError.
    void argument(std::string_view argument, std::string_view flag);
    /// A shell line (of fixed text and shellWord()s). Directives must come before the first.
    void command(std::string_view line);
    const std::string& text() const { return text_; }

    /// Throws ParamError naming `flag` unless `name` fits a Slurm job name (at most 1024 bytes,
    /// no LF or NUL).
    static void checkJobName(std::string_view name, std::string_view flag);
    /// The --output of a log named `literal` (a path, taken as it is) followed by `patterns`
    /// (Slurm's, such as ".slurm-%A_%a.log"): `%` doubled in `literal`. Throws ParamError naming
    /// `flag` for a backslash in `literal` (it would turn the patterns off), or for a result
    /// longer than 4096 bytes.
    static std::string logPattern(std::string_view literal, std::string_view patterns, std::string_view flag);

private:
    std::string text_;
    bool commands_ = false;
};

/// The checks of an Open Job Description template's values: each returns its value, or throws
/// ParamError naming `flag`.
struct OpenJd {
    /// The most characters of a job parameter's value, and of a job's name.
    static constexpr int kMaxParameterCharacters = 1024;
    static constexpr int kMaxNameCharacters = 128;
    /// A job parameter's value: UTF-8 of at most 1024 characters.
    static std::string parameterValue(const std::string& value, std::string_view flag);
    /// A job's name: UTF-8 of 1 to 128 characters, none of them in Unicode's Cc category.
    static std::string jobName(const std::string& name, std::string_view flag);
    /// `name` cut to at most 128 characters (whole UTF-8 sequences); `name` as it is if not UTF-8.
    static std::string shortenedName(const std::string& name);
};

}  // namespace dqj::cli
