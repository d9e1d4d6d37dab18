// `lightfarm-server token create|list|revoke|rotate`: the farm's tokens, managed on the data folder
// (while a server runs on it or not).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>
#include <optional>
#include <string>

namespace lf {

class TokenStore;

class TokenCommand {
  public:
    // Adds the `token` subcommand to `app`.
    explicit TokenCommand(CLI::App& app);
    ~TokenCommand();
    // After parsing: runs the command and returns its exit status; nullopt when `token` was not
    // on the command line.
    std::optional<int> Run();

  private:
    int Create();
    int List();
    int Revoke();
    int Rotate();

    std::string data_dir_, name_, role_;
    CLI::App* token_;
    CLI::App* create_;
    CLI::App* list_;
    CLI::App* rotate_;
    std::unique_ptr<TokenStore> store_;
};

}  // namespace lf
