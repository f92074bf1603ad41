//! nptreemap-formats: the dataset model and the readers that turn input bytes into it.
