//! The single integration-test binary (one module per feature, as mdBook and
//! ripgrep do). `support` holds the shared fixtures and helpers.

mod support;

mod architecture;
mod bad_input;
mod battery;
mod browser;
mod build;
mod cli_conventions;
mod cli_errors;
mod colors;
mod copies;
mod crash;
mod degenerate;
mod determinism;
mod escaping;
mod exec;
mod fuzz;
mod incremental;
mod init;
mod label_text;
mod labels;
mod legibility;
mod light_outputs;
mod neighborhood;
mod packaging;
mod page_scripts;
mod paper_data;
mod picture_options;
mod plain_method;
mod random_hierarchies;
mod render_fields;
mod render_refs;
mod safety;
mod serve;
mod sets;
mod similarity_paths;
mod single_dataset;
mod state_place;
mod tabs;
mod threads;
mod warm_start;
mod watch;
mod watch_stale;
mod zero_weights;
