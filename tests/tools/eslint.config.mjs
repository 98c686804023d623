// eslint's rules for the dashboard (server/web/) and its browser test (tests/browser/):
// the recommended set, an error for every finding (tests/web_lint.sh).
import js from '@eslint/js';
import globals from 'globals';

export default [
  js.configs.recommended,
  {
    files: ['server/web/**/*.js'],
    languageOptions: {ecmaVersion: 2022, sourceType: 'module', globals: globals.browser},
  },
  {
    files: ['tests/browser/**/*.mjs'],
    // The page's own code runs in Chromium, through page.evaluate().
    languageOptions: {
      ecmaVersion: 2022,
      sourceType: 'module',
      globals: {...globals.node, ...globals.browser},
    },
  },
  {rules: {'no-unused-vars': ['error', {args: 'none'}]}},
];
